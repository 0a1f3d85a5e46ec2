#pragma once
#include <nlohmann/json.hpp>

namespace mtled {
using json = nlohmann::json;
}
