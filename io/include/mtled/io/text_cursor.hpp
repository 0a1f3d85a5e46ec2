#pragma once
// Reading a mesh file's text with line numbers, so that every complaint about the file can say
// "file:line". The readers mix two ways of reading: by line (Gmsh sections, Abaqus data lines) and by
// whitespace-separated token (legacy VTK, ASCII data arrays), which may run across lines.
#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mtled::mesh_readers {

class TextCursor {
 public:
  // `label` is the file as named in messages; `first_line` is the line `text` starts on in that file.
  TextCursor(std::string_view text, std::string label, long first_line = 1);

  // The next line without its end of line ("\n" or "\r\n"), or nothing at the end of the text. After
  // next_token() it is the rest of the token's line.
  std::optional<std::string_view> next_line();
  // The next whitespace-separated token, or nothing when only whitespace is left.
  std::optional<std::string_view> next_token();
  // The next token; at the end of the text fails with "the file ends while reading WHAT".
  std::string_view expect_token(std::string_view what);
  // Fails with "the file ends while reading WHAT" (for callers that describe WHAT only when needed).
  [[noreturn]] void fail_at_end(std::string_view what);
  // The next `count` bytes as they are (binary data inside a text file), or nothing when fewer are left.
  std::optional<std::string_view> next_bytes(std::size_t count);

  // The line of the last line or token returned (the first line before anything was read).
  long line() const { return last_line_; }
  std::string where() const;           // "label:line"
  std::string where(long line) const;  // "label:line"
  const std::string& label() const { return label_; }
  std::size_t position() const { return position_; }

  // A place to come back to, for looking one token ahead.
  struct Mark {
    std::size_t position;
    long line, last_line;
  };
  Mark mark() const { return {position_, line_, last_line_}; }
  void reset(const Mark& mark) {
    position_ = mark.position;
    line_ = mark.line;
    last_line_ = mark.last_line;
  }

  // How many of `count` items announced by a header to reserve memory for: what is left of the text
  // cannot hold more than one item per `min_bytes` bytes, whatever a damaged header claims.
  std::size_t reservable(long long count, std::size_t min_bytes) const {
    if (count <= 0) return 0;
    const std::size_t left = (text_.size() - position_) / min_bytes + 1;
    return std::min(static_cast<std::size_t>(count), left);
  }

  // Throws InputError(where(), message).
  [[noreturn]] void fail(const std::string& message) const;

 private:
  std::string_view text_;
  std::string label_;
  std::size_t position_ = 0;
  long line_ = 1;       // line of text_[position_]
  long last_line_ = 1;  // line of the last thing returned
};

// Numbers as the mesh formats write them (std::from_chars, plus an optional leading '+'). Nothing when the
// whole token is not a number; non-finite values are refused.
std::optional<double> parse_real(std::string_view token);
std::optional<long long> parse_integer(std::string_view token);

// The same, failing at the cursor's line with "expected WHAT, found "TOKEN"".
double to_real(std::string_view token, const TextCursor& at, std::string_view what);
long long to_integer(std::string_view token, const TextCursor& at, std::string_view what);

std::string_view trim(std::string_view text);
// Splits `line` at runs of spaces and tabs into `fields` (cleared first; reused to avoid allocations).
void split_whitespace(std::string_view line, std::vector<std::string_view>& fields);
// Splits `line` at commas into trimmed fields; a trailing comma does not make an empty last field.
void split_commas(std::string_view line, std::vector<std::string_view>& fields);
// A token shortened for quoting in a message.
std::string quote_token(std::string_view token);
std::string lowercase(std::string_view text);
std::string uppercase(std::string_view text);

}  // namespace mtled::mesh_readers
