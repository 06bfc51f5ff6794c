#include "map3d/map_file.h"

#include <zlib.h>

#include <cstring>
#include <stdexcept>

namespace rmap::map3d {
namespace {

constexpr char kMagic[8] = {'R', 'M', 'A', 'P', 'C', 'U', 'B', '\0'};
constexpr uint32_t kFormatVersion = 1;

class Writer {
 public:
  template <class T>
  void put(T value) {
    static_assert(std::is_trivially_copyable_v<T>);
    char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));  // the format is little-endian, as are the supported hosts
    bytes.append(raw, sizeof(T));
  }
  std::string bytes;
};

class Reader {
 public:
  explicit Reader(std::string_view bytes) : bytes_(bytes) {}
  template <class T>
  T get(const char* what) {
    if (bytes_.size() - pos_ < sizeof(T)) throw std::runtime_error(std::string("map file truncated while reading ") + what);
    T value;
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  size_t remaining() const { return bytes_.size() - pos_; }

 private:
  std::string_view bytes_;
  size_t pos_ = 0;
};

uint32_t crcOf(std::string_view bytes) {
  return static_cast<uint32_t>(
      crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
}

}  // namespace

static_assert(std::endian::native == std::endian::little, "map files are written in host order: little-endian only");

std::string encodeMap(const CuboidMap& map) {
  Writer w;
  w.bytes.append(kMagic, sizeof(kMagic));
  w.put(kFormatVersion);
  const OccupancyParams& o = map.occupancyParams();
  const FusionParams& f = map.fusionParams();
  w.put(map.resolution());
  w.put(o.hit_log_odds);
  w.put(o.miss_log_odds);
  w.put(o.clamp_min_log_odds);
  w.put(o.clamp_max_log_odds);
  w.put(o.occupied_threshold_log_odds);
  w.put(static_cast<uint8_t>(o.sensor_model));
  w.put(o.max_range_m);
  w.put(f.tolerance_log_odds);
  w.put(static_cast<int32_t>(f.fuse_after_scans));
  const size_t count_at = w.bytes.size();
  w.put(uint64_t{0});
  uint64_t blocks = 0;
  map.forEachBlock([&](const BlockView& view) {
    if (view.cuboids.empty()) return;
    ++blocks;
    w.put(view.key.x);
    w.put(view.key.y);
    w.put(view.key.z);
    w.put(static_cast<uint32_t>(view.cuboids.size()));
    for (const PackedCuboid& c : view.cuboids) {
      w.put(c.lo_packed);
      w.put(c.hi_packed);
      w.put(c.log_odds);
    }
  });
  std::memcpy(w.bytes.data() + count_at, &blocks, sizeof(blocks));
  w.put(crcOf(w.bytes));
  return std::move(w.bytes);
}

std::unique_ptr<CuboidMap> decodeMap(std::string_view bytes) {
  if (bytes.size() < sizeof(kMagic) + 4 || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    throw std::runtime_error("not an rmap map file (bad magic)");
  }
  {
    uint32_t stored;
    std::memcpy(&stored, bytes.data() + bytes.size() - 4, 4);
    if (crcOf(bytes.substr(0, bytes.size() - 4)) != stored) {
      throw std::runtime_error("map file is corrupt or truncated (CRC-32 mismatch)");
    }
  }
  Reader r(bytes.substr(sizeof(kMagic), bytes.size() - sizeof(kMagic) - 4));
  const uint32_t version = r.get<uint32_t>("version");
  if (version != kFormatVersion) {
    throw std::runtime_error("unsupported map file version " + std::to_string(version));
  }
  const double resolution = r.get<double>("resolution");
  OccupancyParams o;
  o.hit_log_odds = r.get<float>("hit log-odds");
  o.miss_log_odds = r.get<float>("miss log-odds");
  o.clamp_min_log_odds = r.get<float>("clamp min");
  o.clamp_max_log_odds = r.get<float>("clamp max");
  o.occupied_threshold_log_odds = r.get<float>("occupied threshold");
  const uint8_t model = r.get<uint8_t>("sensor model");
  if (model > static_cast<uint8_t>(SensorModel::kEndpoint)) throw std::runtime_error("map file has an unknown sensor model");
  o.sensor_model = static_cast<SensorModel>(model);
  o.max_range_m = r.get<double>("max range");
  FusionParams f;
  f.tolerance_log_odds = r.get<float>("fusion tolerance");
  f.fuse_after_scans = r.get<int32_t>("fuse after scans");
  std::unique_ptr<CuboidMap> map;
  try {
    map = std::make_unique<CuboidMap>(resolution, o, f);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("map file has invalid parameters: ") + e.what());
  }
  const uint64_t count = r.get<uint64_t>("block count");
  if (count > r.remaining() / 16) throw std::runtime_error("map file block count exceeds its size");
  std::vector<std::pair<BlockKey, std::vector<PackedCuboid>>> blocks;
  blocks.reserve(count);
  for (uint64_t b = 0; b < count; ++b) {
    BlockKey key;
    key.x = r.get<int32_t>("block key");
    key.y = r.get<int32_t>("block key");
    key.z = r.get<int32_t>("block key");
    const uint32_t n = r.get<uint32_t>("cuboid count");
    if (n == 0 || n > kBlockCells || n > r.remaining() / 8) throw std::runtime_error("map file has a bad cuboid count");
    std::vector<PackedCuboid> cuboids(n);
    for (PackedCuboid& c : cuboids) {
      c.lo_packed = r.get<uint16_t>("cuboid");
      c.hi_packed = r.get<uint16_t>("cuboid");
      c.log_odds = r.get<float>("cuboid");
    }
    blocks.emplace_back(key, std::move(cuboids));
  }
  if (r.remaining() != 0) throw std::runtime_error("map file has trailing bytes after its blocks");
  try {
    map->replaceBlocks(std::move(blocks));
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("map file has invalid cuboids: ") + e.what());
  }
  return map;
}

}  // namespace rmap::map3d
