#include "map3d/octomap_ot.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "map3d/octomap_header.h"

namespace rmap::map3d {
namespace {

// OctoMap compares only this prefix of the first line (AbstractOcTree::readHeader).
constexpr std::string_view kOtMagic = "# Octomap OcTree file";

const std::string kOtFormat = "OctoMap .ot";

[[noreturn]] void failOt(const std::string& what) { throw std::runtime_error(kOtFormat + ": " + what); }

/// Bytes of a node's data after its float log-odds, per tree type.
size_t extraNodeBytes(const std::string& id) {
  if (id == "OcTree") return 0;
  if (id == "ColorOcTree") return 3;    // r, g, b
  if (id == "OcTreeStamped") return 4;  // unsigned int timestamp
  failOt(id.empty() ? "header has no id"
                  : "unsupported tree id \"" + id + "\" (OcTree, ColorOcTree or OcTreeStamped)");
}

/// Depth-first reader of the node stream, the inverse of OcTreeBaseImpl::writeNodesRecurs.
class OtNodeReader {
 public:
  OtNodeReader(std::string_view data, size_t extra_bytes, std::vector<OctreeLeaf>& leaves)
      : data_(data), node_bytes_(sizeof(float) + extra_bytes), leaves_(leaves) {}

  /// Reads the node at `depth` whose cube starts at OctoMap key `key`.
  void readNode(int depth, const std::array<int32_t, 3>& key) {
    if (pos_ + node_bytes_ + 1 > data_.size()) failOt("truncated data at byte " + std::to_string(pos_) + " of the tree");
    float log_odds = 0.0f;
    std::memcpy(&log_odds, data_.data() + pos_, sizeof log_odds);  // OctoMap writes the host's order: little-endian
    const unsigned children = static_cast<uint8_t>(data_[pos_ + node_bytes_]);
    const size_t at = pos_;
    pos_ += node_bytes_ + 1;
    ++nodes_;
    const int32_t size = int32_t{1} << (kOctreeDepth - depth);
    if (children == 0) {
      if (!std::isfinite(log_odds)) failOt("leaf at byte " + std::to_string(at) + " has a log-odds that is not finite");
      leaves_.push_back({CellKey{key[0] - kOctreeKeyOffset, key[1] - kOctreeKeyOffset, key[2] - kOctreeKeyOffset},
                         size, log_odds});
      return;
    }
    if (depth == kOctreeDepth) failOt("node with children below the deepest level (depth 16) at byte " + std::to_string(at));
    const int32_t half = size / 2;
    for (int i = 0; i < 8; ++i) {
      if (!((children >> i) & 1u)) continue;
      readNode(depth + 1, {key[0] + ((i & 1) ? half : 0), key[1] + ((i & 2) ? half : 0), key[2] + ((i & 4) ? half : 0)});
    }
  }

  size_t position() const { return pos_; }
  uint64_t nodes() const { return nodes_; }

 private:
  std::string_view data_;
  size_t node_bytes_;
  std::vector<OctreeLeaf>& leaves_;
  size_t pos_ = 0;
  uint64_t nodes_ = 0;
};

}  // namespace

bool looksLikeOt(std::string_view bytes) { return bytes.substr(0, kOtMagic.size()) == kOtMagic; }

OtTree parseOt(std::string_view bytes) {
  const OctreeHeader header = readOctreeHeader(bytes, kOtMagic, kOtFormat);
  OtTree tree;
  tree.id = header.id;
  tree.resolution_m = header.resolution_m;
  const size_t extra = extraNodeBytes(header.id);
  const std::string_view data = bytes.substr(header.data_offset);
  if (isEmptyTree(header, data, kOtFormat)) return tree;
  OtNodeReader reader(data, extra, tree.leaves);
  reader.readNode(0, {0, 0, 0});
  checkTreeEnd(header, data, reader.position(), reader.nodes(), kOtFormat);
  return tree;
}

}  // namespace rmap::map3d
