// Text helpers of the KITTI-style readers (internal to libsamp/data): line
// streaming with a bounded line length, tokens, numbers that must be finite,
// and the 15/16 object columns of a label line, each error naming
// "path:line: field". Defined in kitti_io.cc. Free functions: thread-safe.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "libsamp/data/track.h"

namespace samp::kitti_text {

// Calls f(line_number, line) for every line of the file (1-based; a trailing
// '\r' removed); throws when the file cannot be opened or a line is longer
// than 1 MiB. `what` names the kind of file in messages ("oxts", ...).
void ForEachLine(const std::string& path, const char* what,
                 const std::function<void(int line_number, const std::string& line)>& f);
// Whitespace-separated tokens.
std::vector<std::string> Tokenize(const std::string& line);
bool IsBlank(const std::string& line);
// "path:line: ".
std::string At(const std::string& path, int line_number);
// A finite number / an integer, else samp::Error "path:line: field 'token' is not ...".
double ParseDouble(const std::string& token, const std::string& path, int line_number, const char* field);
int ParseInt(const std::string& token, const std::string& path, int line_number, const char* field);
// The names of a --sequence list "A,B,C": each trimmed of blanks, a name of
// digits alone padded with zeros to `digits` (KITTI tracking 4, samp's and
// KITTI stereo's layouts 6); an empty name, a name given twice or an empty
// list is a samp::Error.
std::vector<std::string> ParseSequenceList(const std::string& sequences, size_t digits);
// The object columns "type trunc occ alpha x1 y1 x2 y2 h w l x y z ry [score]"
// starting at tokens[first], with the plausibility checks of ReadLabels.
ObjectLabel ParseObject(const std::vector<std::string>& tokens, size_t first, const std::string& path,
                        int line_number);

}  // namespace samp::kitti_text
