#include "soadyn/multibody/text.hpp"

#include <algorithm>
#include <cstdio>

namespace soadyn {

bool is_valid_utf8(const std::string& text) {
  const auto* p = reinterpret_cast<const unsigned char*>(text.data());
  const auto* end = p + text.size();
  while (p < end) {
    const unsigned c = *p;
    int n = 0;
    unsigned cp = 0, min = 0;
    if (c < 0x80) n = 0, cp = c;
    else if ((c & 0xE0) == 0xC0) n = 1, cp = c & 0x1F, min = 0x80;
    else if ((c & 0xF0) == 0xE0) n = 2, cp = c & 0x0F, min = 0x800;
    else if ((c & 0xF8) == 0xF0) n = 3, cp = c & 0x07, min = 0x10000;
    else return false;
    if (end - p < n + 1) return false;
    for (int k = 1; k <= n; ++k) {
      if ((p[k] & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (p[k] & 0x3F);
    }
    if (n > 0 && (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF))) return false;
    p += n + 1;
  }
  return true;
}

std::string printable(const std::string& text) {
  bool plain = is_valid_utf8(text);
  for (unsigned char c : text) plain = plain && (c >= 0x20 && c != 0x7f);
  if (plain) return text;
  std::string shown;
  for (unsigned char c : text) {
    char hex[8];
    std::snprintf(hex, sizeof hex, "\\x%02x", c);
    shown += c >= 0x20 && c < 0x7f ? std::string(1, char(c)) : std::string(hex);
  }
  return shown;
}

std::string excerpt(const std::string& text, size_t max_chars) {
  if (text.size() <= max_chars) return printable(text);
  size_t cut = max_chars;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;  // not inside a character
  return printable(text.substr(0, cut)) + "… (" + std::to_string(text.size()) + " bytes)";
}

namespace {
size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] != b[j - 1])});
      diag = up;
    }
  }
  return row[b.size()];
}

}  // namespace

std::string did_you_mean(const std::string& got, const std::vector<std::string>& choices) {
  std::string best;
  size_t best_d = std::string::npos;
  const size_t near = std::max<size_t>(2, got.size() / 3);
  for (const auto& c : choices) {
    // the distance is at least the lengths' difference: a choice that far off is never suggested
    // (and a 5 MB value costs no 5 MB × |choice| table)
    if ((got.size() > c.size() ? got.size() - c.size() : c.size() - got.size()) > near) continue;
    const size_t d = edit_distance(got, c);
    if (d < best_d) best_d = d, best = c;
  }
  if (!best.empty() && best_d <= near) return "; did you mean '" + excerpt(best) + "'?";
  // at most 20 choices, each shown as text and cut at 60 bytes
  std::string all;
  for (size_t k = 0; k < choices.size() && k < 20; ++k) all += (all.empty() ? "" : ", ") + excerpt(choices[k]);
  if (choices.size() > 20) all += ", … (" + std::to_string(choices.size()) + " in all)";
  return choices.empty() ? "" : " (expected one of: " + all + ")";
}

std::string short_number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

std::string exact_number(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

}  // namespace soadyn
