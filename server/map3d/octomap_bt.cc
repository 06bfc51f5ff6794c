#include "map3d/octomap_bt.h"

#include "map3d/octomap_header.h"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace rmap::map3d {
namespace {

// OctoMap compares only this prefix of the first line (AbstractOccupancyOcTree::readBinary).
constexpr std::string_view kBtMagic = "# Octomap OcTree binary file";
constexpr int kTreeDepth = kOctreeDepth;
constexpr int32_t kKeyOffset = kOctreeKeyOffset;

// 2-bit child codes as OctoMap's std::bitset puts them: child i of a byte
// occupies bits 2i (set for free and inner) and 2i+1 (set for occupied and inner).
constexpr unsigned kFreeLeaf = 1;
constexpr unsigned kOccupiedLeaf = 2;
constexpr unsigned kInnerNode = 3;

const std::string kBtFormat = "OctoMap .bt";

[[noreturn]] void failBt(const std::string& what) { throw std::runtime_error(kBtFormat + ": " + what); }

OctreeHeader readHeader(std::string_view bytes) {
  OctreeHeader h = readOctreeHeader(bytes, kBtMagic, kBtFormat);
  // "1" is the deprecated id OctoMap still maps to OcTree.
  if (h.id != "OcTree" && h.id != "1") {
    failBt(h.id.empty() ? "header has no id" : "unsupported tree id \"" + h.id + "\" (only OcTree)");
  }
  return h;
}

/// Depth-first reader of the node stream, the inverse of OctoMap's writeBinaryNode.
class BtNodeReader {
 public:
  BtNodeReader(std::string_view data, std::vector<BtLeaf>& leaves) : data_(data), leaves_(leaves) {}

  /// Reads the inner node at `depth` whose cube starts at OctoMap key `key`.
  void readInner(int depth, const std::array<int32_t, 3>& key) {
    if (pos_ + 2 > data_.size()) failBt("truncated data at byte " + std::to_string(pos_) + " of the tree");
    // Byte 1 holds children 0-3, byte 2 children 4-7, two bits each from the lowest.
    const unsigned codes = static_cast<unsigned>(static_cast<uint8_t>(data_[pos_])) |
                           (static_cast<unsigned>(static_cast<uint8_t>(data_[pos_ + 1])) << 8);
    pos_ += 2;
    ++nodes_;
    const int child_depth = depth + 1;
    const int32_t child_size = int32_t{1} << (kTreeDepth - child_depth);
    // Leaves and subtrees interleaved in child order give depth-first (Morton) order.
    for (int i = 0; i < 8; ++i) {
      const unsigned code = (codes >> (2 * i)) & 3u;
      if (code == 0) continue;
      const std::array<int32_t, 3> child{key[0] + ((i & 1) ? child_size : 0), key[1] + ((i & 2) ? child_size : 0),
                                         key[2] + ((i & 4) ? child_size : 0)};
      if (code == kInnerNode) {
        if (child_depth == kTreeDepth) {
          failBt("inner node below the deepest level (depth 16) at byte " + std::to_string(pos_ - 2));
        }
        readInner(child_depth, child);
      } else {
        ++nodes_;
        leaves_.push_back({CellKey{child[0] - kKeyOffset, child[1] - kKeyOffset, child[2] - kKeyOffset}, child_size,
                           code == kOccupiedLeaf});
      }
    }
  }

  size_t position() const { return pos_; }
  uint64_t nodes() const { return nodes_; }

 private:
  std::string_view data_;
  std::vector<BtLeaf>& leaves_;
  size_t pos_ = 0;
  uint64_t nodes_ = 0;
};

/// Spreads the low 16 bits of v to every third bit (bit b goes to bit 3b).
uint64_t spreadBits3(uint64_t v) {
  v &= 0xffff;
  v = (v | (v << 16)) & 0x0000ff0000ffULL;
  v = (v | (v << 8)) & 0x00f00f00f00fULL;
  v = (v | (v << 4)) & 0x0c30c30c30c3ULL;
  v = (v | (v << 2)) & 0x249249249249ULL;
  return v;
}

/// Morton code of the OctoMap keys: the three bits of level d (from the top)
/// are OctoMap's child index, x in the lowest bit.
uint64_t mortonCode(const CellKey& c) {
  return spreadBits3(static_cast<uint64_t>(c.x + kKeyOffset)) |
         (spreadBits3(static_cast<uint64_t>(c.y + kKeyOffset)) << 1) |
         (spreadBits3(static_cast<uint64_t>(c.z + kKeyOffset)) << 2);
}

/// An entry: (Morton code of the cube's lowest cell << 6) | (log2 of its edge << 1) | occupied.
constexpr int kEntryCodeShift = 6;
uint64_t cubeEntry(const CellKey& min_cell, int log2_size, bool occupied) {
  return (mortonCode(min_cell) << kEntryCodeShift) | (static_cast<uint64_t>(log2_size) << 1) | (occupied ? 1u : 0u);
}
int entryLog2Size(uint64_t e) { return static_cast<int>((e >> 1) & 31u); }

/// Writes entries sorted by code, of disjoint aligned cubes of edge at most 2^15 cells.
class BtNodeWriter {
 public:
  explicit BtNodeWriter(std::string& out) : out_(out) {}

  /// Writes the subtree of the node at `depth` holding the entries [begin, end)
  /// (non-empty) and returns its code in the parent. A cube as large as the
  /// node is the node, a leaf. A node whose 8 children are leaves of one state
  /// is pruned: its bytes are taken back and it becomes a leaf. The root
  /// (depth 0) is always written.
  unsigned write(const uint64_t* begin, const uint64_t* end, int depth) {
    if (end - begin == 1 && entryLog2Size(*begin) == kTreeDepth - depth) {
      return (*begin & 1u) ? kOccupiedLeaf : kFreeLeaf;
    }
    const size_t at = out_.size();
    out_.append(2, '\0');
    const int shift = kEntryCodeShift + 3 * (kTreeDepth - 1 - depth);
    unsigned codes = 0;
    const uint64_t* first = begin;
    for (unsigned i = 0; i < 8 && first != end; ++i) {
      const uint64_t* last = std::partition_point(first, end, [&](uint64_t e) { return ((e >> shift) & 7u) <= i; });
      if (last != first) codes |= write(first, last, depth + 1) << (2 * i);
      first = last;
    }
    if (depth > 0 && (codes == 0x5555u || codes == 0xaaaau)) {  // all free or all occupied leaves
      out_.resize(at);
      return codes & 3u;
    }
    out_[at] = static_cast<char>(codes & 0xffu);
    out_[at + 1] = static_cast<char>(codes >> 8);
    return kInnerNode;
  }

 private:
  std::string& out_;
};

/// Nodes in a written stream: the root plus every non-empty child code.
uint64_t countNodes(std::string_view data) {
  uint64_t n = data.empty() ? 0 : 1;
  for (char c : data) {
    for (int i = 0; i < 4; ++i) n += ((static_cast<uint8_t>(c) >> (2 * i)) & 3u) != 0;
  }
  return n;
}

}  // namespace

bool looksLikeBt(std::string_view bytes) { return bytes.substr(0, kBtMagic.size()) == kBtMagic; }

BtTree parseBt(std::string_view bytes) {
  const OctreeHeader header = readHeader(bytes);
  BtTree tree;
  tree.resolution_m = header.resolution_m;
  const std::string_view data = bytes.substr(header.data_offset);
  if (isEmptyTree(header, data, kBtFormat)) return tree;
  BtNodeReader reader(data, tree.leaves);
  reader.readInner(0, {0, 0, 0});
  checkTreeEnd(header, data, reader.position(), reader.nodes(), kBtFormat);
  return tree;
}

namespace {

void checkResolution(double resolution_m, const char* who) {
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m)) {
    throw std::invalid_argument(std::string(who) + ": resolution must be finite and > 0, got " +
                                std::to_string(resolution_m));
  }
}

/// The file around the tree of `entries` (sorted by code, cubes disjoint).
std::string writeEntries(double resolution_m, const std::vector<uint64_t>& entries) {
  std::string data;
  if (!entries.empty()) BtNodeWriter(data).write(entries.data(), entries.data() + entries.size(), 0);

  char res[32];  // holds any double in shortest round-trip form
  char* res_end = std::to_chars(res, res + sizeof res, resolution_m).ptr;
  std::string out;
  out.reserve(data.size() + 160);
  out += kBtMagic;
  out += "\n# (feel free to add / change comments, but leave the first line as it is!)\n#\nid OcTree\nsize ";
  out += std::to_string(countNodes(data));
  out += "\nres ";
  out.append(res, res_end);
  out += "\ndata\n";
  out += data;
  return out;
}

}  // namespace

std::string writeBt(double resolution_m, std::vector<BtCell> cells) {
  checkResolution(resolution_m, "writeBt");
  std::vector<uint64_t> entries;
  entries.reserve(cells.size());
  for (const BtCell& c : cells) {
    if (!cellInRange(c.cell)) {
      throw std::invalid_argument("writeBt: cell (" + std::to_string(c.cell.x) + ", " + std::to_string(c.cell.y) +
                                  ", " + std::to_string(c.cell.z) + ") is outside [-32768, 32768)");
    }
    entries.push_back(cubeEntry(c.cell, 0, c.occupied));
  }
  cells = {};  // release the input before sorting
  // Stable by code so that among duplicates the last input stays last and wins.
  const auto byCode = [](uint64_t a, uint64_t b) { return (a >> kEntryCodeShift) < (b >> kEntryCodeShift); };
  std::stable_sort(entries.begin(), entries.end(), byCode);
  size_t n = 0;
  for (size_t i = 0; i < entries.size(); ++i) {
    if (n > 0 && !byCode(entries[n - 1], entries[i])) {
      entries[n - 1] = entries[i];
    } else {
      entries[n++] = entries[i];
    }
  }
  entries.resize(n);
  return writeEntries(resolution_m, entries);
}

std::string writeBtCubes(double resolution_m, const std::vector<BtLeaf>& cubes) {
  checkResolution(resolution_m, "writeBtCubes");
  std::vector<uint64_t> entries;
  entries.reserve(cubes.size());
  for (const BtLeaf& c : cubes) {
    const int32_t s = c.size_cells;
    const CellKey last{c.min_cell.x + s - 1, c.min_cell.y + s - 1, c.min_cell.z + s - 1};
    const auto aligned = [&](int32_t cell) { return (cell + kKeyOffset) % s == 0; };
    if (s < 1 || s > kKeyOffset || !std::has_single_bit(static_cast<uint32_t>(s)) || !cellInRange(c.min_cell) ||
        !cellInRange(last) || !aligned(c.min_cell.x) || !aligned(c.min_cell.y) || !aligned(c.min_cell.z)) {
      throw std::invalid_argument("writeBtCubes: the cube at (" + std::to_string(c.min_cell.x) + ", " +
                                  std::to_string(c.min_cell.y) + ", " + std::to_string(c.min_cell.z) + ") of edge " +
                                  std::to_string(s) + " is not an aligned power of two of at most 32768 cells");
    }
    entries.push_back(cubeEntry(c.min_cell, std::countr_zero(static_cast<uint32_t>(s)), c.occupied));
  }
  std::sort(entries.begin(), entries.end());
  return writeEntries(resolution_m, entries);
}

}  // namespace rmap::map3d
