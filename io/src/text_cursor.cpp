#include "mtled/io/text_cursor.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>

#include "mtled/errors.hpp"

namespace mtled::mesh_readers {

namespace {
bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }
}  // namespace

TextCursor::TextCursor(std::string_view text, std::string label, long first_line)
    : text_(text), label_(std::move(label)), line_(first_line), last_line_(first_line) {}

std::optional<std::string_view> TextCursor::next_line() {
  if (position_ >= text_.size()) return std::nullopt;
  const std::size_t start = position_;
  std::size_t end = text_.find('\n', start);
  last_line_ = line_;
  if (end == std::string_view::npos) {
    end = text_.size();
    position_ = end;
  } else {
    position_ = end + 1;
    ++line_;
  }
  std::string_view line = text_.substr(start, end - start);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return line;
}

std::optional<std::string_view> TextCursor::next_token() {
  while (position_ < text_.size() && is_space(text_[position_])) {
    if (text_[position_] == '\n') ++line_;
    ++position_;
  }
  if (position_ >= text_.size()) return std::nullopt;
  const std::size_t start = position_;
  while (position_ < text_.size() && !is_space(text_[position_])) ++position_;
  last_line_ = line_;
  return text_.substr(start, position_ - start);
}

std::string_view TextCursor::expect_token(std::string_view what) {
  const auto token = next_token();
  if (!token) fail_at_end(what);
  return *token;
}

void TextCursor::fail_at_end(std::string_view what) {
  last_line_ = line_;
  fail(fmt::format("the file ends while reading {}: it is truncated or a count in it is wrong; export it again", what));
}


std::optional<std::string_view> TextCursor::next_bytes(std::size_t count) {
  if (count > text_.size() - position_) return std::nullopt;
  const std::string_view bytes = text_.substr(position_, count);
  line_ += static_cast<long>(std::count(bytes.begin(), bytes.end(), '\n'));  // as a text editor numbers them
  position_ += count;
  last_line_ = line_;
  return bytes;
}

std::string TextCursor::where() const { return where(last_line_); }
std::string TextCursor::where(long line) const { return fmt::format("{}:{}", label_, line); }

void TextCursor::fail(const std::string& message) const { throw InputError(where(), message); }

std::optional<double> parse_real(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return std::nullopt;
  double value = 0.0;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (error != std::errc() || end != token.data() + token.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::optional<long long> parse_integer(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return std::nullopt;
  long long value = 0;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (error != std::errc() || end != token.data() + token.size()) return std::nullopt;
  return value;
}

double to_real(std::string_view token, const TextCursor& at, std::string_view what) {
  const auto value = parse_real(token);
  if (!value) at.fail(fmt::format("expected {} (a finite number), found {}", what, quote_token(token)));
  return *value;
}

long long to_integer(std::string_view token, const TextCursor& at, std::string_view what) {
  const auto value = parse_integer(token);
  if (!value) at.fail(fmt::format("expected {} (an integer), found {}", what, quote_token(token)));
  return *value;
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
  return text;
}

void split_whitespace(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > start) fields.push_back(line.substr(start, i - start));
  }
}

void split_commas(std::string_view line, std::vector<std::string_view>& fields) {
  fields.clear();
  line = trim(line);
  if (line.empty()) return;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      const auto last = trim(line.substr(start));
      if (!last.empty()) fields.push_back(last);
      return;
    }
    fields.push_back(trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
}

std::string quote_token(std::string_view token) {
  constexpr std::size_t kLongest = 40;
  std::string text(token.substr(0, kLongest));
  for (char& c : text)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return fmt::format("\"{}{}\"", text, token.size() > kLongest ? "..." : "");
}

std::string lowercase(std::string_view text) {
  std::string result(text);
  for (char& c : result)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return result;
}

std::string uppercase(std::string_view text) {
  std::string result(text);
  for (char& c : result)
    if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  return result;
}

}  // namespace mtled::mesh_readers
