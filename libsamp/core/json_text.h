// JSON text that never fails on the bytes of a string: paths, names and CAD
// metadata may hold any bytes (a folder name in Latin-1, a 0xFF in an input
// file), and nlohmann::json::dump() throws on invalid UTF-8 by default, which
// would lose a result at the last step. DumpJson writes every byte sequence
// that is not valid UTF-8 as U+FFFD (the replacement character) instead.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace samp {

// `indent` < 0: compact, one line; otherwise pretty-printed with that indent.
inline std::string DumpJson(const nlohmann::json& json, int indent = -1) {
  return json.dump(indent, ' ', /*ensure_ascii=*/false, nlohmann::json::error_handler_t::replace);
}

}  // namespace samp
