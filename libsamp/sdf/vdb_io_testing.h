// Test hooks of libsamp/sdf/vdb_io.cc, for tests/sdf/vdb_io_test.cc: writing
// with a chosen compression, re-sealing a file after a test edited its bytes
// on purpose (as an attacker would: the file checksum is no signature), and
// the byte offsets of the payload fields samp's decoder reads. Not for
// production code.
#pragma once

#include <string>
#include <vector>

#include "libsamp/sdf/vdb_io.h"
#include "libsamp/sdf/vdb_payload.h"

namespace samp {

enum class VdbTestCompression { kBlosc, kZip };

// WriteVdb with the values stored blosc- or zip-compressed (plus active-value
// mask compression in both cases).
void WriteVdbForTesting(const std::string& path, const GridSpec& spec,
                        const std::vector<DenseGrid>& grids, const VdbMetadata& metadata,
                        float background, VdbTestCompression compression);

// Rewrites samp_file_bytes and samp_file_checksum of the .vdb at `path` so
// that its current bytes pass the file checksum.
void ResealVdbForTesting(const std::string& path);

// Reads the valid .vdb at `path` and returns, per grid, where the decoder
// found each payload field (throws like ReadVdb on an invalid file).
std::vector<VdbPayloadLayout> VdbPayloadLayoutForTesting(const std::string& path);

}  // namespace samp
