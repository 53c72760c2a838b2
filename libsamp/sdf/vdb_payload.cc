#include "libsamp/sdf/vdb_payload.h"

#include <blosc.h>
#include <zlib.h>

#include <array>
#include <cmath>
#include <cstring>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/sdf/byte_reader.h"

namespace samp {
namespace {

// io::COMPRESS_* (openvdb/io/Compression.h).
constexpr uint32_t kCompressZip = 0x1;
constexpr uint32_t kCompressActiveMask = 0x2;
constexpr uint32_t kCompressBlosc = 0x4;

// The per-node byte of io::writeCompressedValues that says which inactive
// values were left out and how to restore them.
enum NodeMetadata : int8_t {
  kNoMaskOrInactiveVals = 0,     // inactive values are +background
  kNoMaskAndMinusBg = 1,         // inactive values are -background
  kNoMaskAndOneInactiveVal = 2,  // inactive values are one stored value
  kMaskAndNoInactiveVals = 3,    // selection mask picks -background or +background
  kMaskAndOneInactiveVal = 4,    // selection mask picks a stored value or +background
  kMaskAndTwoInactiveVals = 5,   // selection mask picks one of two stored values
  kNoMaskAndAllVals = 6,         // every value is stored
};

constexpr char kMapType[] = "UniformScaleTranslateMap";
// Tree_float_5_4_3: log2 of the node sides in voxels (leaf 8, lower internal
// 8 x 16 = 128, upper internal 128 x 32 = 4096).
constexpr int kLeafLog2 = 3;
constexpr int kLowerLog2 = 4 + kLeafLog2;
constexpr int kUpperLog2 = 5 + kLowerLog2;
constexpr size_t kBloscHeaderBytes = BLOSC_MIN_HEADER_LENGTH;

// A node's bit mask of 2^(3 log2dim) bits, stored as OpenVDB's NodeMask
// (uint64 words, bit n in word n / 64 at n % 64).
template <int kLog2Dim>
struct NodeMask {
  static constexpr int kSize = 1 << (3 * kLog2Dim);
  static constexpr int kWords = kSize / 64;
  std::array<uint64_t, kWords> words{};

  bool On(int n) const { return (words[size_t(n >> 6)] >> (n & 63)) & 1u; }
  int Count() const {
    int count = 0;
    for (uint64_t w : words) count += __builtin_popcountll(w);
    return count;
  }
  bool Intersects(const NodeMask& other) const {
    for (int w = 0; w < kWords; ++w) {
      if (words[size_t(w)] & other.words[size_t(w)]) return true;
    }
    return false;
  }
  bool operator==(const NodeMask& other) const { return words == other.words; }
  // Calls f(n) for every set bit n, in increasing order.
  template <typename F>
  void ForEachOn(F f) const {
    for (int w = 0; w < kWords; ++w) {
      for (uint64_t word = words[size_t(w)]; word != 0; word &= word - 1) {
        f(w * 64 + __builtin_ctzll(word));
      }
    }
  }
  void Read(ByteReader* in, const char* what) { in->ReadArray(words.data(), size_t(kWords), what); }
};

using Coord = std::array<int64_t, 3>;

std::string Format(const Coord& c) {
  std::ostringstream out;
  out << "(" << c[0] << ", " << c[1] << ", " << c[2] << ")";
  return out.str();
}

// Local coordinates of slot n of a node of side 2^log2dim (x slowest, z fastest).
Coord SlotOffset(int n, int log2dim) {
  const int mask = (1 << log2dim) - 1;
  return {int64_t(n >> (2 * log2dim)), int64_t((n >> log2dim) & mask), int64_t(n & mask)};
}

uint32_t FloatBits(float value) {
  uint32_t bits;
  std::memcpy(&bits, &value, sizeof(bits));
  return bits;
}

uint32_t LittleEndian32(const char* data) {
  uint32_t value;
  std::memcpy(&value, data, sizeof(value));
  return value;
}

// Printable form of a name read from the file (at most 64 bytes).
std::string Printable(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size() && i < 64; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    out += (c >= 0x20 && c < 0x7f) ? char(c) : '?';
  }
  if (text.size() > 64) out += "...";
  return out;
}

// A node named in errors ("leaf at (8, 0, 16)"), formatted only on failure.
struct NodeName {
  const char* kind;
  Coord origin;
};
std::ostream& operator<<(std::ostream& out, const NodeName& node) {
  return out << node.kind << " at " << Format(node.origin);
}

struct LeafRecord {
  Coord origin;
  NodeMask<kLeafLog2> mask;
};

class GridDecoder {
 public:
  GridDecoder(const std::string& bytes, const std::string& path, const VdbGridPayloadRef& ref,
              const Eigen::Vector3i& dims, VdbPayloadLayout* layout)
      : bytes_(bytes),
        in_(bytes, path + ": grid '" + ref.name + "'", ref.end),
        ref_(ref),
        dims_{dims.x(), dims.y(), dims.z()},
        layout_(layout) {
    std::ostringstream box;
    box << "the " << dims.x() << " x " << dims.y() << " x " << dims.z() << " grid";
    box_ = box.str();
  }

  void Decode(std::vector<float>* values, VdbGridTransform* transform, float* background) {
    SAMP_CHECK(ref_.end <= in_.end() && ref_.transform <= ref_.block && ref_.block <= ref_.end)
        << Where() << ": inconsistent offsets (transform " << ref_.transform << ", block "
        << ref_.block << ", end " << ref_.end << ")";
    SAMP_CHECK((ref_.compression & kCompressActiveMask) &&
               ((ref_.compression & ~kCompressActiveMask) == kCompressBlosc ||
                (ref_.compression & ~kCompressActiveMask) == kCompressZip))
        << Where() << ": stored with compression '" << VdbCompressionName(ref_.compression)
        << "' (flags " << ref_.compression
        << "); samp reads the layout it writes: blosc or zip, each with active values";
    blosc_ = (ref_.compression & kCompressBlosc) != 0;
    // The transform and the topology lie before the block offset, the
    // buffers between it and the end offset: each is read within its range.
    in_.Seek(int64_t(ref_.transform), "the transform");
    in_.SetEnd(ref_.block);
    ReadTransform(transform);

    const int64_t voxels = dims_[0] * dims_[1] * dims_[2];
    ReadTopologyHeader();
    values_ = values;
    values_->assign(size_t(voxels), background_);
    ReadRoot();
    SAMP_CHECK(in_.pos() == ref_.block)
        << Where() << ": the topology ends at byte " << in_.pos()
        << ", the grid descriptor puts the buffers at byte " << ref_.block;
    if (layout_ != nullptr) layout_->block = in_.pos();
    in_.SetEnd(ref_.end);
    ReadLeafBuffers();
    SAMP_CHECK(in_.pos() == ref_.end)
        << Where() << ": " << (ref_.end - in_.pos()) << " bytes after the last of its "
        << leaves_.size() << " leaves (corrupt file)";
    if (layout_ != nullptr) layout_->end = in_.pos();
    SAMP_CHECK(ref_.announced_active_voxels < 0 || ref_.announced_active_voxels == active_voxels_)
        << Where() << ": its masks and tiles hold " << active_voxels_
        << " active voxels, its metadata file_voxel_count says " << ref_.announced_active_voxels;
    *background = background_;
  }

 private:
  const std::string& Where() const { return in_.context(); }

  // Transform::write: the map's type name, then UniformScaleTranslateMap::write
  // (ScaleTranslateMap): translation, scale, voxel size, inverse scale,
  // inverse scale squared, half the inverse scale (Vec3d each).
  void ReadTransform(VdbGridTransform* transform) {
    const size_t begin = in_.pos();
    if (layout_ != nullptr) layout_->transform = begin;
    const uint32_t name_bytes = in_.Read<uint32_t>("transform type name length");
    const std::string name = in_.ReadBytes(std::min<uint64_t>(name_bytes, 64), "transform type name");
    SAMP_CHECK(name_bytes == sizeof(kMapType) - 1 && name == kMapType)
        << Where() << ": its transform is a '" << Printable(name) << (name_bytes > 64 ? "..." : "")
        << "', samp reads only the " << kMapType << " it writes";
    double v[18];
    in_.ReadArray(v, 18, "transform fields");
    for (double x : v) {
      SAMP_CHECK(std::isfinite(x)) << Where() << ": its transform holds a non-finite number";
    }
    const double scale = v[3];
    SAMP_CHECK(scale > 0 && v[4] == scale && v[5] == scale)
        << Where() << ": its transform's scale (" << v[3] << ", " << v[4] << ", " << v[5]
        << ") is not one positive voxel size";
    // The derived fields as ScaleTranslateMap's constructor computes them.
    const double inverse = 1.0 / scale;
    const double expected[4] = {scale, inverse, inverse * inverse, inverse / 2};
    for (int f = 0; f < 4; ++f) {
      for (int a = 0; a < 3; ++a) {
        SAMP_CHECK(v[6 + 3 * f + a] == expected[f])
            << Where() << ": its transform's derived field " << (6 + 3 * f + a) << " is "
            << v[6 + 3 * f + a] << ", its scale " << scale << " makes it " << expected[f];
      }
    }
    // The voxel size as OpenVDB's index-to-world map gives it ((1 s + t) -
    // (0 s + t) along x: 0.10000000000000009 for s = 0.1, t = -3), which is
    // what samp read before it had its own decoder: fits and evaluations
    // reproduce earlier runs to the last bit.
    transform->voxel_size = (scale + v[0]) - v[0];
    transform->origin = Eigen::Vector3d(v[0], v[1], v[2]);
    transform->serialized = bytes_.substr(begin, in_.pos() - begin);
  }

  // TreeBase::writeTopology (buffer count) and the head of RootNode::writeTopology.
  void ReadTopologyHeader() {
    const int32_t buffer_count = in_.Read<int32_t>("tree buffer count");
    SAMP_CHECK(buffer_count == 1) << Where() << ": its tree announces " << buffer_count
                                  << " buffers per node, samp writes 1";
    if (layout_ != nullptr) layout_->background = in_.pos();
    background_ = in_.Read<float>("background value");
    SAMP_CHECK(std::isfinite(background_))
        << Where() << ": its background value " << background_ << " is not finite";
    background_bits_ = FloatBits(background_);
  }

  bool OriginInBox(const Coord& c) const {
    for (int a = 0; a < 3; ++a) {
      if (c[a] < 0 || c[a] >= dims_[a]) return false;
    }
    return true;
  }
  bool RegionInBox(const Coord& c, int log2) const {
    for (int a = 0; a < 3; ++a) {
      if (c[a] < 0 || c[a] + (int64_t(1) << log2) > dims_[a]) return false;
    }
    return true;
  }

  // Writes `value` over the part of the cube [c, c + 2^log2) inside the box.
  void FillRegion(const Coord& c, int log2, float value) {
    if (FloatBits(value) == background_bits_) return;  // already the background
    const int64_t side = int64_t(1) << log2;
    int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max<int64_t>(c[a], 0);
      hi[a] = std::min<int64_t>(c[a] + side, dims_[a]);
      if (lo[a] >= hi[a]) return;
    }
    float* data = values_->data();
    for (int64_t z = lo[2]; z < hi[2]; ++z) {
      for (int64_t y = lo[1]; y < hi[1]; ++y) {
        float* row = data + (dims_[0] * (y + dims_[1] * z));
        std::fill(row + lo[0], row + hi[0], value);
      }
    }
  }

  // A tile at `c` of side 2^log2 (the root's; internal nodes check theirs
  // before reading their values): an active one must lie inside the box.
  void AddTile(const Coord& c, int log2, float value, bool active, const char* kind) {
    if (active) {
      SAMP_CHECK(RegionInBox(c, log2))
          << Where() << ": active " << kind << " tile at " << Format(c) << " (side "
          << (int64_t(1) << log2) << ") reaches outside " << box_;
      active_voxels_ += int64_t(1) << (3 * log2);
    }
    FillRegion(c, log2, value);
  }

  // RootNode::writeTopology after the background: tile and child counts, the
  // tiles (origin, value, active flag), then each child's origin and topology.
  void ReadRoot() {
    if (layout_ != nullptr) layout_->tile_count = in_.pos();
    const uint32_t tiles = in_.Read<uint32_t>("root tile count");
    if (layout_ != nullptr) layout_->child_count = in_.pos();
    const uint32_t children = in_.Read<uint32_t>("root child count");
    int64_t room = 1;
    for (int a = 0; a < 3; ++a) room *= (dims_[a] + (int64_t(1) << kUpperLog2) - 1) >> kUpperLog2;
    SAMP_CHECK(uint64_t(tiles) + children <= uint64_t(room))
        << Where() << ": its root holds " << tiles << " tiles and " << children
        << " children, " << box_ << " has room for " << room;
    std::vector<Coord> tile_origins;
    for (uint32_t t = 0; t < tiles; ++t) {
      const Coord c = ReadRootOrigin("root tile");
      SAMP_CHECK(tile_origins.empty() || tile_origins.back() < c)
          << Where() << ": root tile at " << Format(c) << " out of order or twice";
      tile_origins.push_back(c);
      const float value = in_.Read<float>("root tile value");
      const uint8_t active = in_.Read<uint8_t>("root tile active flag");
      SAMP_CHECK(active <= 1) << Where() << ": root tile at " << Format(c) << " has active flag "
                              << int(active);
      AddTile(c, kUpperLog2, value, active == 1, "root");
    }
    Coord previous{-1, -1, -1};
    for (uint32_t n = 0; n < children; ++n) {
      if (layout_ != nullptr) layout_->root_child_origins.push_back(in_.pos());
      const Coord c = ReadRootOrigin("internal node");
      SAMP_CHECK(n == 0 || previous < c)
          << Where() << ": internal node at " << Format(c) << " out of order or twice";
      SAMP_CHECK(!std::binary_search(tile_origins.begin(), tile_origins.end(), c))
          << Where() << ": internal node at " << Format(c) << " where the root has a tile";
      previous = c;
      ReadInternal<5>(c);
    }
  }

  Coord ReadRootOrigin(const char* kind) {
    int32_t v[3];
    in_.ReadArray(v, 3, kind);
    const Coord c{v[0], v[1], v[2]};
    const int64_t align = (int64_t(1) << kUpperLog2) - 1;
    SAMP_CHECK(((c[0] | c[1] | c[2]) & align) == 0)
        << Where() << ": " << kind << " at " << Format(c) << " is not on a multiple of "
        << (align + 1);
    SAMP_CHECK(OriginInBox(c)) << Where() << ": " << kind << " at " << Format(c) << " outside "
                               << box_;
    return c;
  }

  // InternalNode::writeTopology: child mask, value mask, the compressed slot
  // values, then the children in mask order. kLog2Dim 5 (children are lower
  // internal nodes) or 4 (children are leaves, whose topology is their value mask).
  template <int kLog2Dim>
  void ReadInternal(const Coord& origin) {
    constexpr int kChildLog2 = kLog2Dim == 5 ? kLowerLog2 : kLeafLog2;
    const char* const kind = kLog2Dim == 5 ? "upper internal node" : "lower internal node";
    if (layout_ != nullptr) {
      layout_->internal_child_masks.push_back(in_.pos());
      layout_->internal_origins.push_back(
          Eigen::Vector3i(int(origin[0]), int(origin[1]), int(origin[2])));
      layout_->internal_levels.push_back(kLog2Dim);
    }
    NodeMask<kLog2Dim> child_mask, value_mask;
    child_mask.Read(&in_, "child mask");
    value_mask.Read(&in_, "value mask");
    SAMP_CHECK(!child_mask.Intersects(value_mask))
        << Where() << ": " << kind << " at " << Format(origin)
        << " marks slots as both child and active tile";
    auto child_origin = [&](int n) {
      const Coord local = SlotOffset(n, kLog2Dim);
      return Coord{origin[0] + (local[0] << kChildLog2), origin[1] + (local[1] << kChildLog2),
                   origin[2] + (local[2] << kChildLog2)};
    };
    // Every child inside the box, every active tile wholly inside it, before
    // anything is read for them.
    child_mask.ForEachOn([&](int n) {
      const Coord c = child_origin(n);
      SAMP_CHECK(OriginInBox(c)) << Where() << ": "
                                 << NodeName{kLog2Dim == 5 ? "lower internal node" : "leaf", c}
                                 << " outside " << box_;
    });
    value_mask.ForEachOn([&](int n) {
      const Coord c = child_origin(n);
      SAMP_CHECK(RegionInBox(c, kChildLog2))
          << Where() << ": active tile of the " << kind << " at " << Format(c) << " (side "
          << (int64_t(1) << kChildLog2) << ") reaches outside " << box_;
      active_voxels_ += int64_t(1) << (3 * kChildLog2);
    });
    std::vector<float>& slots = kLog2Dim == 5 ? upper_slots_ : lower_slots_;
    slots.resize(size_t(NodeMask<kLog2Dim>::kSize));
    ReadCompressedValues(value_mask, slots.data(), NodeName{kind, origin});
    // Tiles: only values other than the background change the dense grid.
    for (int n = 0; n < NodeMask<kLog2Dim>::kSize; ++n) {
      if (FloatBits(slots[size_t(n)]) == background_bits_ || child_mask.On(n)) continue;
      FillRegion(child_origin(n), kChildLog2, slots[size_t(n)]);
    }
    child_mask.ForEachOn([&](int n) {
      const Coord c = child_origin(n);
      if constexpr (kLog2Dim == 5) {
        ReadInternal<4>(c);
      } else {
        LeafRecord leaf;
        leaf.origin = c;
        if (layout_ != nullptr) {
          VdbPayloadLayout::Leaf entry;
          entry.origin = Eigen::Vector3i(int(c[0]), int(c[1]), int(c[2]));
          entry.topology_mask = in_.pos();
          layout_->leaves.push_back(entry);
        }
        leaf.mask.Read(&in_, "leaf value mask");
        CheckLeafActiveInBox(leaf);
        active_voxels_ += leaf.mask.Count();
        leaves_.push_back(leaf);
      }
    });
  }

  // A leaf straddling the box edge may hold voxels outside it, inactive only.
  // Word lx of a leaf mask holds the voxels (lx, ly, lz) at bit 8 ly + lz.
  void CheckLeafActiveInBox(const LeafRecord& leaf) const {
    if (RegionInBox(leaf.origin, kLeafLog2)) return;
    const int side = 1 << kLeafLog2;
    int hi[3];
    for (int a = 0; a < 3; ++a) hi[a] = int(std::min<int64_t>(side, dims_[a] - leaf.origin[a]));
    uint64_t inside_word = 0;
    for (int ly = 0; ly < hi[1]; ++ly) inside_word |= ((uint64_t(1) << hi[2]) - 1) << (side * ly);
    for (int lx = 0; lx < side; ++lx) {
      const uint64_t outside = leaf.mask.words[size_t(lx)] & ~(lx < hi[0] ? inside_word : 0);
      if (outside == 0) continue;
      const int bit = __builtin_ctzll(outside);
      const Coord c{leaf.origin[0] + lx, leaf.origin[1] + bit / side, leaf.origin[2] + bit % side};
      SAMP_THROW() << Where() << ": leaf at " << Format(leaf.origin) << " has an active voxel at "
                   << Format(c) << " outside " << box_;
    }
  }

  // io::readCompressedValues for a node of NodeMask<L>::kSize values with
  // active-mask compression: metadata byte, up to two inactive values, the
  // selection mask, then one chunk with the stored values.
  template <int kLog2Dim>
  void ReadCompressedValues(const NodeMask<kLog2Dim>& value_mask, float* out, const NodeName& node,
                            VdbPayloadLayout::Leaf* entry = nullptr) {
    constexpr int kCount = NodeMask<kLog2Dim>::kSize;
    if (entry != nullptr) entry->metadata = in_.pos();
    const int8_t metadata = in_.Read<int8_t>("node metadata byte");
    SAMP_CHECK(metadata >= kNoMaskOrInactiveVals && metadata <= kNoMaskAndAllVals)
        << Where() << ": " << node << " has value metadata byte " << int(metadata)
        << ", OpenVDB writes 0 to 6";
    float inactive1 = background_;
    float inactive0 = metadata == kNoMaskOrInactiveVals ? background_ : -background_;
    if (metadata == kNoMaskAndOneInactiveVal || metadata == kMaskAndOneInactiveVal ||
        metadata == kMaskAndTwoInactiveVals) {
      inactive0 = in_.Read<float>("inactive value");
      if (metadata == kMaskAndTwoInactiveVals) inactive1 = in_.Read<float>("second inactive value");
    }
    NodeMask<kLog2Dim> selection;
    if (metadata == kMaskAndNoInactiveVals || metadata == kMaskAndOneInactiveVal ||
        metadata == kMaskAndTwoInactiveVals) {
      selection.Read(&in_, "selection mask");
      SAMP_CHECK(!selection.Intersects(value_mask))
          << Where() << ": " << node << " has a selection mask that selects active values";
    }
    const int stored = metadata == kNoMaskAndAllVals ? kCount : value_mask.Count();
    if (stored == kCount) {
      ReadChunk(size_t(stored) * sizeof(float), reinterpret_cast<char*>(out), node, stored, entry);
      return;
    }
    stored_.resize(size_t(stored));
    ReadChunk(size_t(stored) * sizeof(float), reinterpret_cast<char*>(stored_.data()), node, stored,
              entry);
    // Inactive values first (inactive1 where the selection mask says), then
    // the stored values in mask order.
    std::fill(out, out + kCount, inactive0);
    selection.ForEachOn([&](int n) { out[n] = inactive1; });
    int next = 0;
    value_mask.ForEachOn([&](int n) { out[n] = stored_[size_t(next++)]; });
  }

  // io::readData's chunk: an int64 size (negative: that many raw bytes follow),
  // then a blosc or zip stream that must decompress to exactly `expected` bytes.
  void ReadChunk(size_t expected, char* out, const NodeName& node, int values,
                 VdbPayloadLayout::Leaf* entry) {
    if (entry != nullptr) entry->chunk_size = in_.pos();
    const int64_t size = in_.Read<int64_t>("chunk size");
    if (entry != nullptr) {
      entry->chunk = in_.pos();
      entry->chunk_bytes = size;
    }
    if (size <= 0) {
      const uint64_t raw = 0 - uint64_t(size);
      SAMP_CHECK(raw == expected) << Where() << ": uncompressed chunk of " << raw << " bytes, "
                                  << node << " holds " << expected << " (" << values
                                  << " stored values)";
      in_.ReadArray(out, expected, "uncompressed values");
      return;
    }
    const char* src = in_.Take(uint64_t(size), blosc_ ? "blosc chunk" : "zip chunk");
    char dummy = 0;
    char* dest = expected > 0 ? out : &dummy;
    if (blosc_) {
      SAMP_CHECK(uint64_t(size) >= kBloscHeaderBytes)
          << Where() << ": blosc chunk of " << size << " bytes in " << node << ", shorter than its "
          << kBloscHeaderBytes << "-byte header";
      const uint32_t nbytes = LittleEndian32(src + 4);
      const uint32_t cbytes = LittleEndian32(src + 12);
      SAMP_CHECK(nbytes == expected) << Where() << ": blosc chunk announces " << nbytes
                                     << " bytes, " << node << " holds " << expected << " ("
                                     << values << " stored values)";
      SAMP_CHECK(cbytes == uint64_t(size))
          << Where() << ": blosc chunk of " << node << " says it is " << cbytes
          << " bytes long, its size prefix says " << size;
      size_t validated = 0;
      SAMP_CHECK(blosc_cbuffer_validate(src, size_t(size), &validated) == 0 && validated == expected)
          << Where() << ": blosc refuses the chunk header of " << node;
      if (expected > 0) {
        const int n = blosc_decompress_ctx(src, dest, expected, /*numinternalthreads=*/1);
        SAMP_CHECK(n >= 0 && size_t(n) == expected)
            << Where() << ": blosc chunk of " << node << " does not decompress to its " << expected
            << " bytes (blosc returned " << n << ")";
      }
    } else {
      uLongf dest_bytes = uLongf(expected);
      const int status = uncompress(reinterpret_cast<Bytef*>(dest), &dest_bytes,
                                    reinterpret_cast<const Bytef*>(src), uLong(size));
      SAMP_CHECK(status == Z_OK && dest_bytes == expected)
          << Where() << ": zip chunk of " << size << " bytes in " << node
          << " does not inflate to the " << expected << " bytes it holds (zlib: "
          << (status == Z_OK ? "wrong size" : zError(status)) << ")";
    }
  }

  // RootNode/InternalNode/LeafNode::writeBuffers: per leaf in topology order,
  // its value mask again and its compressed values.
  void ReadLeafBuffers() {
    std::array<float, NodeMask<kLeafLog2>::kSize> leaf_values;
    float* data = values_->data();
    for (size_t l = 0; l < leaves_.size(); ++l) {
      const LeafRecord& leaf = leaves_[l];
      VdbPayloadLayout::Leaf* entry = layout_ != nullptr ? &layout_->leaves[l] : nullptr;
      const NodeName node{"leaf", leaf.origin};
      if (entry != nullptr) entry->buffer_mask = in_.pos();
      NodeMask<kLeafLog2> mask;
      mask.Read(&in_, "leaf value mask");
      SAMP_CHECK(mask == leaf.mask) << Where() << ": " << node
                                    << " has a value mask in its buffer that differs from its "
                                       "topology";
      ReadCompressedValues(mask, leaf_values.data(), node, entry);
      // Voxels outside the box are inactive (checked with the topology) and dropped.
      const int side = 1 << kLeafLog2;
      int hi[3];
      for (int a = 0; a < 3; ++a) hi[a] = int(std::min<int64_t>(side, dims_[a] - leaf.origin[a]));
      for (int lz = 0; lz < hi[2]; ++lz) {
        for (int ly = 0; ly < hi[1]; ++ly) {
          float* row = data + (leaf.origin[0] + dims_[0] * (leaf.origin[1] + ly +
                                                             dims_[1] * (leaf.origin[2] + lz)));
          const float* column = leaf_values.data() + (ly << kLeafLog2) + lz;
          for (int lx = 0; lx < hi[0]; ++lx) row[lx] = column[lx << (2 * kLeafLog2)];
        }
      }
    }
  }

  const std::string& bytes_;
  ByteReader in_;
  const VdbGridPayloadRef& ref_;
  const int64_t dims_[3];
  VdbPayloadLayout* layout_;
  std::string box_;
  bool blosc_ = true;
  float background_ = 0.0f;
  uint32_t background_bits_ = 0;
  std::vector<float>* values_ = nullptr;
  std::vector<LeafRecord> leaves_;
  std::vector<float> upper_slots_, lower_slots_, stored_;
  int64_t active_voxels_ = 0;
};

}  // namespace

std::string VdbCompressionName(uint32_t flags) {
  if (flags == 0) return "none";
  std::string name;
  if (flags & kCompressZip) name += "zip + ";
  if (flags & kCompressBlosc) name += "blosc + ";
  if (flags & kCompressActiveMask) name += "active values + ";
  if (flags & ~(kCompressZip | kCompressBlosc | kCompressActiveMask)) name += "unknown + ";
  name.resize(name.size() - 3);
  return name;
}

void DecodeVdbFloatGrid(const std::string& bytes, const std::string& path,
                        const VdbGridPayloadRef& ref, const Eigen::Vector3i& dims,
                        std::vector<float>* values, VdbGridTransform* transform,
                        float* background, VdbPayloadLayout* layout) {
  SAMP_CHECK(dims.minCoeff() > 0) << path << ": grid '" << ref.name << "': empty grid dims";
  GridDecoder decoder(bytes, path, ref, dims, layout);
  decoder.Decode(values, transform, background);
}

}  // namespace samp
