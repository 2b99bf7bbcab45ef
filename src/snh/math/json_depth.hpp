#pragma once
// How deeply a JSON text nests, found without parsing it: readers that build a tree recursively (tinygltf
// turns a glTF's extras into nested values) overflow the stack on a file of a few kilobytes that opens
// thousands of arrays, so the text is measured first and refused past a bound.
#include <cstddef>
#include <string_view>

namespace snh {

/// The deepest nesting of arrays and objects in `text` (brackets inside strings, escapes included, do not
/// count), scanning no further once `limit` is exceeded: the result is then limit + 1. Malformed JSON is
/// measured as far as it goes (the parser reports what is wrong with it).
[[nodiscard]] std::size_t json_depth(std::string_view text, std::size_t limit);

}  // namespace snh
