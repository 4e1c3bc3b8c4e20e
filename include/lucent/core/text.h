// Text from files and command lines quoted in messages: made safe to print on a terminal.
#pragma once
#include <string>
#include <string_view>

namespace lucent {

// `text` with what a terminal would act on escaped as \xNN: control characters (C0, DEL, and C1 in
// UTF-8), and bytes that are not part of valid UTF-8 (a raw 0x9b is an 8-bit terminal's CSI).
// Printable UTF-8 is kept.
std::string printable(std::string_view text);
// The same for a message of several lines: each line made printable, the line breaks kept.
std::string printableLines(std::string_view text);

// A short excerpt of text read from a file, for a message: printable, at most `most` characters
// (cut with "..."), so that a message never reproduces a file's contents.
std::string excerpt(std::string_view text, size_t most = 32);

}  // namespace lucent
