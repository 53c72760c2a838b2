// samp's own bounded decoder of the grid payload of a .vdb file, for the one
// layout WriteVdb writes (docs/model_format.md, "Validation on load"): a
// FloatGrid (Tree_float_5_4_3, full floats) on a UniformScaleTranslateMap,
// values compressed with blosc or zip plus active-value mask compression, as
// OpenVDB 10's writer lays them out (io::Archive::writeGrid, RootNode,
// InternalNode and LeafNode writeTopology/writeBuffers, io::writeCompressedValues).
//
// OpenVDB's own reader trusts every count and size in a file; this decoder
// checks each of them against the bytes left in the grid and against the grid
// box before it allocates or writes anything, and fills the dense grid
// directly (no OpenVDB tree is built). Internal to libsamp/sdf (ReadVdb).
// Thread-safe (no shared state).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace samp {

// The grid's index-to-world map: world = origin + voxel_size * index.
struct VdbGridTransform {
  double voxel_size = 0.0;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  // The serialized map (type name and fields), to compare grids exactly.
  std::string serialized;
};

// Where the decoder found the fields of one grid (byte offsets in the file),
// for tests that corrupt them on purpose.
struct VdbPayloadLayout {
  size_t transform = 0;    // the uint32 length of the map type name
  size_t background = 0;   // root background value (float)
  size_t tile_count = 0;   // root tile count (uint32), then the child count
  size_t child_count = 0;
  // Per level-5 node, in file order: the offset of its origin (3 int32) at the root.
  std::vector<size_t> root_child_origins;
  // Per internal node (level 5 and 4, depth-first file order): its child mask
  // (its value mask follows), and the node's origin.
  std::vector<size_t> internal_child_masks;
  std::vector<Eigen::Vector3i> internal_origins;
  std::vector<int> internal_levels;  // log2 of its side in children: 5 (upper) or 4 (lower)
  struct Leaf {
    Eigen::Vector3i origin = Eigen::Vector3i::Zero();
    size_t topology_mask = 0;  // value mask in the topology (8 uint64)
    size_t buffer_mask = 0;    // value mask again in the buffers
    size_t metadata = 0;       // the per-node metadata byte
    size_t chunk_size = 0;     // int64 size prefix of the value chunk
    size_t chunk = 0;          // the chunk itself
    int64_t chunk_bytes = 0;   // the size prefix's value
  };
  std::vector<Leaf> leaves;  // in file order
  size_t block = 0;          // first byte of the buffers
  size_t end = 0;            // one past the grid's last byte
};

// One grid's payload as recorded in its descriptor and header.
struct VdbGridPayloadRef {
  std::string name;
  uint32_t compression = 0;  // the grid's io::COMPRESS_* flags
  size_t transform = 0;      // first byte after the grid metadata
  size_t block = 0;          // the recorded block offset (start of the buffers)
  size_t end = 0;            // the recorded end offset
  // The grid's file_voxel_count metadata, or -1 when absent.
  int64_t announced_active_voxels = -1;
};

// Decodes the grid at `ref` in `bytes` onto the box [0, dims) of a dense
// x-fastest grid: `*values` gets dims.prod() floats (the background where no
// node covers a voxel), `*transform` the grid's map, `*background` its
// background. Throws samp::Error "<path>: grid '<name>': ..." naming the field
// and the figures on anything but the layout above, a node outside the box or
// twice, counts and sizes that disagree with the masks, the bytes left or the
// recorded offsets. `dims` must have been checked against the memory budget.
// `layout`, when not null, receives the offsets of the fields (tests).
void DecodeVdbFloatGrid(const std::string& bytes, const std::string& path,
                        const VdbGridPayloadRef& ref, const Eigen::Vector3i& dims,
                        std::vector<float>* values, VdbGridTransform* transform,
                        float* background, VdbPayloadLayout* layout = nullptr);

// The io::COMPRESS_* flags ReadVdb accepts, in words ("blosc + active values").
std::string VdbCompressionName(uint32_t flags);

}  // namespace samp
