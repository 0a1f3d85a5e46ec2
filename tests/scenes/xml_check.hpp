#pragma once
// A small well-formedness check for the SVG files mtled writes (no XML library needed): one root element,
// balanced and properly nested tags, quoted attributes, only the predefined or numeric entities, no text
// outside the root.
#include <cctype>
#include <string>
#include <vector>

namespace mtled::test {

namespace xml_detail {

inline std::string at(std::size_t k) { return " at byte " + std::to_string(k); }

inline bool name_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == ':' || c == '-' || c == '.';
}

// The length of a valid entity at k, else 0.
inline std::size_t entity(const std::string& text, std::size_t k) {
  for (const char* e : {"&amp;", "&lt;", "&gt;", "&quot;", "&apos;"})
    if (text.compare(k, std::string(e).size(), e) == 0) return std::string(e).size();
  if (text.compare(k, 2, "&#") == 0) {
    const std::size_t end = text.find(';', k);
    if (end != std::string::npos && end > k + 2 && end < k + 10) return end - k + 1;
  }
  return 0;
}

// The attributes of the start tag <name opened at `tag`, from k (just after the name) to its ">" or "/>": "" and k just
// past the tag (self_closing for "/>"), else what is wrong.
inline std::string read_attributes(const std::string& text, const std::string& name, std::size_t tag, std::size_t& k,
                                   bool& self_closing) {
  while (true) {
    while (k < text.size() && std::isspace(static_cast<unsigned char>(text[k]))) ++k;
    if (k >= text.size()) return "unterminated tag <" + name + ">" + at(tag);
    if (text.compare(k, 2, "/>") == 0 || text[k] == '>') {
      self_closing = text[k] == '/';
      k += self_closing ? 2 : 1;
      return "";
    }
    const std::size_t attribute = k;
    while (k < text.size() && name_char(text[k])) ++k;
    if (k == attribute || k + 1 >= text.size() || text[k] != '=' || (text[k + 1] != '"' && text[k + 1] != '\''))
      return "bad attribute in <" + name + ">" + at(attribute);
    const char quote = text[k + 1];
    k += 2;
    while (k < text.size() && text[k] != quote) {
      if (text[k] == '<') return "'<' in an attribute value" + at(k);
      if (text[k] == '&') {
        const std::size_t n = entity(text, k);
        if (n == 0) return "bad entity in an attribute value" + at(k);
        k += n;
        continue;
      }
      ++k;
    }
    if (k >= text.size()) return "unterminated attribute value" + at(attribute);
    ++k;
  }
}

}  // namespace xml_detail

// "" when `text` is well-formed, else what is wrong and where (byte offset).
inline std::string xml_problem(const std::string& text) {
  using xml_detail::at, xml_detail::name_char;
  std::vector<std::string> open;
  int roots = 0;
  std::size_t i = 0;
  if (text.compare(0, 5, "<?xml") == 0) {
    const std::size_t end = text.find("?>");
    if (end == std::string::npos) return "unterminated XML declaration";
    i = end + 2;
  }
  while (i < text.size()) {
    const char c = text[i];
    if (c == '<') {
      if (text.compare(i, 4, "<!--") == 0) {
        const std::size_t end = text.find("-->", i);
        if (end == std::string::npos) return "unterminated comment" + at(i);
        i = end + 3;
        continue;
      }
      if (i + 1 < text.size() && text[i + 1] == '/') {
        std::size_t k = i + 2;
        while (k < text.size() && name_char(text[k])) ++k;
        const std::string name = text.substr(i + 2, k - i - 2);
        while (k < text.size() && std::isspace(static_cast<unsigned char>(text[k]))) ++k;
        if (k >= text.size() || text[k] != '>') return "bad end tag" + at(i);
        if (open.empty() || open.back() != name) return "end tag </" + name + "> does not match" + at(i);
        open.pop_back();
        i = k + 1;
        continue;
      }
      std::size_t k = i + 1;
      while (k < text.size() && name_char(text[k])) ++k;
      const std::string name = text.substr(i + 1, k - i - 1);
      if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0]))) return "bad tag name" + at(i);
      if (open.empty() && ++roots > 1) return "a second root element" + at(i);
      bool self_closing = false;
      if (std::string problem = xml_detail::read_attributes(text, name, i, k, self_closing); !problem.empty())
        return problem;
      if (!self_closing) open.push_back(name);
      i = k;
      continue;
    }
    if (c == '&') {
      const std::size_t n = xml_detail::entity(text, i);
      if (n == 0) return "bad entity" + at(i);
      i += n;
      continue;
    }
    if (open.empty() && !std::isspace(static_cast<unsigned char>(c))) return "text outside the root element" + at(i);
    ++i;
  }
  if (!open.empty()) return "<" + open.back() + "> is never closed";
  if (roots != 1) return "no root element";
  return "";
}

}  // namespace mtled::test
