// JSON as Lucent prints and stores it.
#pragma once
#include <string>

namespace lucent {

// `json` as text, where a string that is not valid UTF-8 (a file name in another encoding) has its
// invalid bytes replaced by U+FFFD: nlohmann::json would throw instead, after the files were written.
template <class Json>
std::string jsonText(const Json& json, int indent = -1) {
  return json.dump(indent, ' ', false, Json::error_handler_t::replace);
}

}  // namespace lucent
