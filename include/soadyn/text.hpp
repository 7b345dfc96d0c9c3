// Text checks shared by every layer: names go into UTF-8 attributes and messages.
#pragma once

#include <string>

namespace soadyn {

// True if `text` is well-formed UTF-8 (no overlong forms, surrogates or code points past U+10FFFF).
bool is_valid_utf8(const std::string& text);

// `text` as it can be shown in a one-line message: unchanged when it is valid UTF-8 without
// control characters, else every byte outside printable ASCII written as \xHH.
std::string printable(const std::string& text);

}  // namespace soadyn
