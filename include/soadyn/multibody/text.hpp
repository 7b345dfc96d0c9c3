// Text checks shared by every layer: names go into UTF-8 attributes and messages.
#pragma once

#include <string>
#include <vector>

namespace soadyn {

// True if `text` is well-formed UTF-8 (no overlong forms, surrogates or code points past U+10FFFF).
bool is_valid_utf8(const std::string& text);

// `text` as it can be shown in a one-line message: unchanged when it is valid UTF-8 without
// control characters, else every byte outside printable ASCII written as \xHH.
std::string printable(const std::string& text);

// A user's value for a message: printable(text), cut after its first `max_chars` bytes (at a
// UTF-8 character's start) with "… (N bytes)" when longer, so no message holds a whole file.
std::string excerpt(const std::string& text, size_t max_chars = 60);

// "; did you mean 'x'?" for the choice nearest `got` (Levenshtein distance at most max(2, |got|/3)),
// else " (expected one of: a, b, …)"; "" when there are no choices
std::string did_you_mean(const std::string& got, const std::vector<std::string>& choices);

// x for a message, as printf's %g (six significant digits), and exactly, as %.17g (it reads back
// as the same double: JSON, values a user copies)
std::string short_number(double x);
std::string exact_number(double x);

}  // namespace soadyn
