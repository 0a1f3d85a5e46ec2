#include "mtled/process_lock.hpp"

#include <map>
#include <string>

namespace mtled {

std::mutex& process_lock(std::string_view library) {
  static std::mutex guard;
  static std::map<std::string, std::mutex, std::less<>> locks;  // a map's elements never move
  const std::lock_guard hold(guard);
  auto it = locks.find(library);
  if (it == locks.end()) it = locks.try_emplace(std::string(library)).first;
  return it->second;
}

}  // namespace mtled
