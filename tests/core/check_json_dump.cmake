# ctest core/JsonText.NoDumpOutsideTheSafeWriter: every JSON text samp makes
# goes through DumpJson (libsamp/core/json_text.h), which writes bytes that are
# not UTF-8 as U+FFFD; nlohmann::json::dump() with its defaults throws on them
# (a Latin-1 folder name once lost a whole fit at the last step). Fails listing
# every other `.dump(` in libsamp/ and tools/.
#   cmake -DSOURCE_DIR=<repository> -P check_json_dump.cmake
cmake_policy(SET CMP0057 NEW)
set(allowed
  # The safe writer itself.
  "libsamp/core/json_text.h")
file(GLOB_RECURSE sources RELATIVE "${SOURCE_DIR}"
     "${SOURCE_DIR}/libsamp/*.cc" "${SOURCE_DIR}/libsamp/*.h"
     "${SOURCE_DIR}/tools/*.cc" "${SOURCE_DIR}/tools/*.h")
set(found "")
foreach(source IN LISTS sources)
  if(source IN_LIST allowed)
    continue()
  endif()
  file(STRINGS "${SOURCE_DIR}/${source}" lines REGEX "\\.dump\\(")
  foreach(line IN LISTS lines)
    string(STRIP "${line}" line)
    string(APPEND found "\n  ${source}: ${line}")
  endforeach()
endforeach()
if(found)
  message(FATAL_ERROR "nlohmann::json::dump() outside DumpJson (use DumpJson from "
                      "libsamp/core/json_text.h):${found}")
endif()
list(LENGTH sources count)
message(STATUS "${count} files checked: no .dump( outside DumpJson")
