// A JSON document read into nlohmann's ordered_json by our own SAX builder: nesting bounded
// (kMaxJsonDepth), a repeated key caught, key order kept, in linear time. Scenes and
// assignments are read by it alike, so both refuse the same documents in the same words.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rayfarm/diagnostic.h"

namespace rayfarm {

// A key as a JSON Pointer token (RFC 6901: ~ as ~0, / as ~1).
std::string json_pointer_token(std::string_view key);

// A JSON number as an option's text: whole numbers as integers (100000, not 1e+05, for 100000,
// 1e5 or 100000.0 alike; an unsigned 64-bit seed exactly), others as format_number writes
// them.
std::string json_number_text(const nlohmann::ordered_json& number);

// The document, or nothing after an error: invalid JSON ("json-syntax", at its line and
// column) or nesting too deep ("json-depth", at its path). A key given twice in one object is
// an error at its path ("duplicate-key"), and the document is still returned, holding the
// first value, so that its reader can say what else is wrong.
std::optional<nlohmann::ordered_json> parse_json_tree(std::string_view text, Diagnostics& diags);

// Where each JSON Pointer of `pointers` lies in `text`: the byte offset of a member's key or
// an element's value. A pointer that names nothing there (a member left out) gets the place
// of the nearest value that holds it; the root is at the document's start. For ordering
// errors as the file has them; text that is not JSON gives what could be read of it.
std::vector<std::size_t> json_pointer_offsets(std::string_view text,
                                              const std::vector<std::string>& pointers);

}  // namespace rayfarm
