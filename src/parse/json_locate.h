// Finds where a key path (as JsonReader spells it: "media[0].g") is written in
// the JSON text, so that errors found after parsing can still point at a line
// and column.
#pragma once

#include <cstddef>
#include <string>

namespace vdbmarch {

// Byte offset of the key (for object members) or of the element (for list
// items) at `path`; std::string::npos when the text does not contain it.
size_t locateJsonPath(const std::string& text, const std::string& path);

// 1-based line and column of a byte offset.
void lineAndColumn(const std::string& text, size_t offset, size_t& line, size_t& column);
// The line of `text` holding `offset` (at most 120 characters) and a caret
// under the offset's column, each on its own indented line: the excerpt that
// follows a "file:line:column: message" error.
std::string caretExcerpt(const std::string& text, size_t offset);

}  // namespace vdbmarch
