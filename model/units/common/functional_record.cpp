#include "units/common/functional_record.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "tilevis/fnv1a.h"
#include "units/common/frame_work.h"

namespace tilevis::sim {
namespace {

static_assert(std::endian::native == std::endian::little, "the record is written little-endian, as the host's memory");

constexpr char kMagic[8] = {'T', 'V', 'F', 'R', 'E', 'C', '\r', '\n'};

// The record's checksum: FNV-1a's step on 64-bit little-endian words, then on the last bytes
// (eight times fewer dependent multiplies than bytewise: a record is tens of megabytes).
uint64_t word_fnv1a64(const uint8_t* p, size_t n) {
  uint64_t h = kFnv1a64Basis;
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    uint64_t w;
    std::memcpy(&w, p + i, 8);
    h = (h ^ w) * kFnv1a64Prime;
  }
  return fnv1a64(p + i, n - i, h);
}

// One description of each structure's fields serves writing and reading (Writer, Reader).
template <typename A>
void fields(A& a, geom::Vertex& v) {
  a.io(v.x), a.io(v.y), a.io(v.z);
}
template <typename A>
void fields(A& a, trace::SamplePos& s) {
  a.io(s.x), a.io(s.y);
}
template <typename A>
void fields(A& a, vis::SetupTriangle& t) {
  for (geom::Vertex& v : t.v) fields(a, v);
  a.io(t.id), a.io(t.draw), a.io(t.front), a.io(t.opaque), a.io(t.sample_rate), a.io(t.clipped);
}
template <typename A>
void fields(A& a, vis::SilhouetteEdge& e) {
  fields(a, e.a), fields(a, e.b), a.io(e.draw);
}
template <typename A>
void fields(A& a, vis::Setup& s) {
  a.io(s.width), a.io(s.height), a.io(s.samples), a.io(s.subpixel_bits), a.io(s.depth_bits);
  a.io(s.triangles), a.io(s.silhouettes), a.io(s.triangle_draw);
  vis::SetupStats& st = s.stats;
  for (uint64_t* x : {&st.triangles_in, &st.frustum_culled, &st.clipped, &st.setup_triangles, &st.edge_on,
                      &st.degenerate, &st.back_facing, &st.front_facing, &st.silhouette_edges})
    a.io(*x);
}
template <typename A>
void fields(A& a, TriangleWork& t) {
  for (const auto& f : vis::TileCounters::kFields) a.io(t.*f.second);
  vis::EvuShape& s = t.shape;
  a.io(s.test6_stop), a.io(s.split_edges), a.io(s.crossing_edges), a.io(s.piece_checks), a.io(s.pieces_tested);
  a.io(t.id), a.io(t.draw), a.io(t.depth_tests), a.io(t.fragments_shaded);
}
template <typename A>
void fields(A& a, std::pair<uint32_t, double>& p) {
  a.io(p.first), a.io(p.second);
}
template <typename A>
void fields(A& a, RecordedTile& t) {
  a.io(t.per_pixel), a.io(t.detection_screens), a.io(t.detection_tests);
  a.io(t.tris), a.io_runs(t.samples), a.io(t.areas), a.io(t.visible_triangles);
}
template <typename A>
void fields(A& a, RecordedSegment& s) {
  a.io(s.tiles), a.io(s.triangle_count), a.io(s.edge_count), a.io(s.pair_tests), a.io(s.list_begin), a.io(s.list);
  a.io(s.resolved), a.io_results(s);
}
template <typename A>
void fields(A& a, FunctionalKey& k) {
  a.io(k.frame_fnv1a64), a.io(k.mode), a.io(k.tile_w), a.io(k.tile_h), a.io(k.depth_bits);
  a.io(k.evu_triangle_entries), a.io(k.evu_edge_entries), a.io(k.hybrid_pair_budget), a.io(k.detection_bin);
}
template <typename A>
void fields(A& a, FunctionalRecord& r) {
  fields(a, r.key);
  fields(a, r.setup);
  a.io(r.setup_begin), a.io(r.tri_refs), a.io(r.tri_tests), a.io(r.edge_refs), a.io(r.edge_tests);
  a.io(r.owned_begin), a.io(r.owned), a.io(r.segment_plan), a.io(r.segments);
}

// Integers wider than a byte are LEB128 varints (signed ones zigzagged): most counters,
// indices and ids are small, and the record is several times smaller for it. Bytes, bools and
// doubles are stored as they are.
template <typename T>
constexpr bool kVarint = std::is_integral_v<T> && sizeof(T) > 1;

class Writer {
 public:
  std::vector<uint8_t> bytes;
  // A tile's samples as runs of equal values (count, then value and run length per run): a
  // tile is mostly a few triangles' runs, and samples were most of a record's bytes.
  void io_runs(const std::vector<int32_t>& v) {
    io(uint64_t(v.size()));
    for (size_t i = 0; i < v.size();) {
      size_t j = i + 1;
      while (j < v.size() && v[j] == v[i]) ++j;
      io(v[i]);
      io(uint64_t(j - i));
      i = j;
    }
  }
  template <typename T>
  requires std::is_arithmetic_v<T>
  void io(const T& v) {
    if constexpr (kVarint<T>) {
      uint64_t u = std::is_signed_v<T> ? (uint64_t(int64_t(v)) << 1) ^ uint64_t(int64_t(v) >> 63) : uint64_t(v);
      for (; u >= 0x80; u >>= 7) bytes.push_back(uint8_t(u) | 0x80);
      bytes.push_back(uint8_t(u));
    } else {
      const auto* p = reinterpret_cast<const uint8_t*>(&v);
      bytes.insert(bytes.end(), p, p + sizeof v);
    }
  }
  // Each resolved tile after its length, so that a loaded record finds a tile without decoding
  // the ones before it.
  void io_results(const RecordedSegment& s) {
    if (!s.encoded.empty()) throw std::logic_error("functional record: a loaded record is not written again");
    io(uint64_t(s.results.size()));
    Writer tile;
    for (const RecordedTile& r : s.results) {
      tile.bytes.clear();
      fields(tile, const_cast<RecordedTile&>(r));
      io(uint64_t(tile.bytes.size()));
      bytes.insert(bytes.end(), tile.bytes.begin(), tile.bytes.end());
    }
  }
  template <typename T>
  void io(const std::vector<T>& v) {
    io(uint64_t(v.size()));
    if constexpr (std::is_arithmetic_v<T> && !kVarint<T>) {
      const auto* p = reinterpret_cast<const uint8_t*>(v.data());
      bytes.insert(bytes.end(), p, p + v.size() * sizeof(T));
    } else if constexpr (std::is_arithmetic_v<T>) {
      for (const T& x : v) io(x);
    } else {
      for (const T& x : v) fields(*this, const_cast<T&>(x));
    }
  }
};

class Reader {
 public:
  Reader(const std::string& file, const uint8_t* p, size_t n) : m_file(file), m_p(p), m_n(n) {}
  template <typename T>
  requires std::is_arithmetic_v<T>
  void io(T& v) {
    if constexpr (kVarint<T>) {
      uint64_t u = 0;
      if (m_n - m_at >= 10) {  // the longest varint fits: no bound to check per byte
        const uint8_t* p = m_p + m_at;
        uint8_t b = *p++;
        u = b & 0x7f;
        for (int shift = 7; b & 0x80; shift += 7) {
          b = *p++;
          if (shift == 63 && b > 1) fail("an integer over 64 bits");
          u |= uint64_t(b & 0x7f) << shift;
        }
        m_at = size_t(p - m_p);
      } else {
        for (int shift = 0;; shift += 7) {
          need(1, "a value");
          const uint8_t b = m_p[m_at++];
          if (shift == 63 && b > 1) fail("an integer over 64 bits");
          u |= uint64_t(b & 0x7f) << shift;
          if (!(b & 0x80)) break;
        }
      }
      if constexpr (std::is_signed_v<T>) {
        const int64_t x = int64_t(u >> 1) ^ -int64_t(u & 1);
        if (x < int64_t(std::numeric_limits<T>::min()) || x > int64_t(std::numeric_limits<T>::max()))
          fail("an integer out of its field's range");
        v = T(x);
      } else {
        if (u > uint64_t(std::numeric_limits<T>::max())) fail("an integer out of its field's range");
        v = T(u);
      }
    } else {
      need(sizeof v, "a value");
      std::memcpy(&v, m_p + m_at, sizeof v);
      m_at += sizeof v;
    }
  }
  template <typename T>
  void io(std::vector<T>& v) {
    uint64_t n = 0;
    io(n);
    // Every element takes at least one byte: a count beyond the bytes left is corruption, not
    // an allocation to try.
    if (n > m_n - m_at) fail("a list of " + std::to_string(n) + " elements, beyond the file's end");
    v.resize(size_t(n));
    if constexpr (std::is_arithmetic_v<T> && !kVarint<T>) {
      need(v.size() * sizeof(T), "a list's elements");
      std::memcpy(v.data(), m_p + m_at, v.size() * sizeof(T));
      m_at += v.size() * sizeof(T);
    } else if constexpr (std::is_arithmetic_v<T>) {
      for (T& x : v) io(x);
    } else {
      for (T& x : v) fields(*this, x);
    }
  }
  // The tiles' places only (decoded when replayed: FunctionalRecord::tile).
  void io_results(RecordedSegment& s) {
    uint64_t n = 0;
    io(n);
    if (n > m_n - m_at) fail("a list of " + std::to_string(n) + " tiles, beyond the file's end");
    s.results.clear();
    s.encoded.resize(size_t(n));
    for (auto& e : s.encoded) {
      uint64_t len = 0;
      io(len);
      need(len, "a tile");
      e = {uint64_t(m_at), len};
      m_at += size_t(len);
    }
  }
  void io_runs(std::vector<int32_t>& v) {
    uint64_t n = 0;
    io(n);
    // A tile's samples count in 32 bits: more is corruption, not an allocation to try.
    if (n > uint64_t(std::numeric_limits<uint32_t>::max())) fail("a tile of " + std::to_string(n) + " samples");
    v.resize(size_t(n));
    for (size_t i = 0; i < v.size();) {
      int32_t x = 0;
      uint64_t run = 0;
      io(x);
      io(run);
      if (run == 0 || run > v.size() - i) fail("a run of " + std::to_string(run) + " samples past its tile's " + std::to_string(n));
      std::fill_n(v.begin() + ptrdiff_t(i), size_t(run), x);
      i += size_t(run);
    }
  }
  size_t at() const { return m_at; }
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(m_file + ": offset " + std::to_string(m_at) + ": " + what);
  }

 private:
  void need(size_t k, const char* what) const {
    if (k > m_n - m_at) fail(std::string("truncated: expected ") + what);
  }
  std::string m_file;
  const uint8_t* m_p;
  size_t m_n, m_at = 0;
};

}  // namespace

FunctionalKey functional_key(const trace::Frame& frame, const FrameWorkConfig& c) {
  trace::Trace t;
  t.frames.push_back(frame);
  const std::vector<uint8_t> bytes = trace::encode(t);
  FunctionalKey k;
  k.frame_fnv1a64 = word_fnv1a64(bytes.data(), bytes.size());
  k.mode = uint32_t(c.mode);
  k.tile_w = c.tile_w;
  k.tile_h = c.tile_h;
  k.depth_bits = c.depth_bits;
  k.evu_triangle_entries = c.evu_triangle_entries;
  k.evu_edge_entries = c.evu_edge_entries;
  k.hybrid_pair_budget = c.hybrid_pair_budget;
  k.detection_bin = c.detection_bin;
  return k;
}

namespace {

std::string hex64(uint64_t h) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(h));
  return s;
}

}  // namespace

std::string cache_file_name(const FunctionalKey& key, const std::string& plan_parameters) {
  Writer w;
  fields(w, const_cast<FunctionalKey&>(key));
  w.io(uint32_t(FunctionalRecord::kVersion));
  w.bytes.insert(w.bytes.end(), plan_parameters.begin(), plan_parameters.end());
  return hex64(word_fnv1a64(w.bytes.data(), w.bytes.size())) + ".rec";
}

std::string key_differences(const FunctionalKey& r, const FunctionalKey& n) {
  std::string out;
  auto differ = [&](const char* what, const std::string& a, const std::string& b) {
    if (a != b) out += std::string(out.empty() ? "" : "; ") + what + ": the record has " + a + ", this run " + b;
  };
  differ("the frame (FNV-1a 64 of its trace encoding, by words)", hex64(r.frame_fnv1a64), hex64(n.frame_fnv1a64));
  differ("sim.mode", to_string(Mode(r.mode)), to_string(Mode(n.mode)));
  differ("sim.tile_width", std::to_string(r.tile_w), std::to_string(n.tile_w));
  differ("sim.tile_height", std::to_string(r.tile_h), std::to_string(n.tile_h));
  differ("sim.depth_bits", std::to_string(r.depth_bits), std::to_string(n.depth_bits));
  differ("evu.triangle_list_entries", std::to_string(r.evu_triangle_entries), std::to_string(n.evu_triangle_entries));
  differ("evu.edge_list_entries", std::to_string(r.evu_edge_entries), std::to_string(n.evu_edge_entries));
  differ("evu.hybrid_pair_budget", std::to_string(r.hybrid_pair_budget), std::to_string(n.hybrid_pair_budget));
  differ("evu.detection_bin", std::to_string(r.detection_bin), std::to_string(n.detection_bin));
  return out;
}

void FunctionalRecord::save(const std::filesystem::path& path) const {
  Writer w;
  auto raw = [&w](const auto& v) {
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    w.bytes.insert(w.bytes.end(), p, p + sizeof v);
  };
  w.bytes.insert(w.bytes.end(), kMagic, kMagic + sizeof kMagic);
  raw(kVersion);
  fields(w, const_cast<FunctionalRecord&>(*this));
  raw(word_fnv1a64(w.bytes.data(), w.bytes.size()));
  // One temporary name per process: runs of a sweep recording the same file do not mix bytes
  // (the last rename wins, and every record it may leave is whole).
  std::filesystem::path tmp = path;
  tmp += ".tmp." + std::to_string(getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(w.bytes.data()), std::streamsize(w.bytes.size()));
    out.close();
    if (!out) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw std::runtime_error(path.string() + ": writing the functional record failed");
    }
  }
  std::filesystem::rename(tmp, path);
}

namespace {

// The record's file mapped read-only (no copy into a zeroed buffer: records are tens of
// megabytes, and fresh pages cost more than the decoding).
class MappedFile {
 public:
  explicit MappedFile(const std::string& name) {
    const int fd = ::open(name.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw std::runtime_error(name + ": cannot read the functional record");
    struct stat st {};
    if (::fstat(fd, &st) != 0) {
      ::close(fd);
      throw std::runtime_error(name + ": cannot read the functional record");
    }
    m_size = size_t(std::max<off_t>(st.st_size, 0));
    if (m_size > 0) {
      void* p = ::mmap(nullptr, m_size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
      if (p == MAP_FAILED) {
        ::close(fd);
        throw std::runtime_error(name + ": reading the functional record failed");
      }
      m_data = static_cast<const uint8_t*>(p);
    }
    ::close(fd);
  }
  ~MappedFile() {
    if (m_data) ::munmap(const_cast<uint8_t*>(m_data), m_size);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  const uint8_t* data() const { return m_data; }
  size_t size() const { return m_size; }

 private:
  const uint8_t* m_data = nullptr;
  size_t m_size = 0;
};

}  // namespace

FunctionalRecord FunctionalRecord::load(const std::filesystem::path& path) {
  const std::string name = path.string();
  const auto file = std::make_shared<const MappedFile>(name);
  const uint8_t* const bytes = file->data();
  const size_t size = file->size();
  const size_t head = sizeof kMagic + sizeof(uint32_t), tail = sizeof(uint64_t);
  if (size < sizeof kMagic || std::memcmp(bytes, kMagic, sizeof kMagic) != 0)
    throw std::runtime_error(name + ": not a TileVis functional record (no \"TVFREC\" magic)");
  if (size < head + tail)
    throw std::runtime_error(name + ": truncated functional record (" + std::to_string(size) + " bytes)");
  uint32_t version = 0;
  std::memcpy(&version, bytes + sizeof kMagic, sizeof version);
  if (version != kVersion)
    throw std::runtime_error(name + ": functional record format version " + std::to_string(version) +
                             ", this build reads version " + std::to_string(kVersion) + " (record it again)");
  uint64_t sum = 0;
  std::memcpy(&sum, bytes + size - tail, tail);
  if (sum != word_fnv1a64(bytes, size - tail))
    throw std::runtime_error(name + ": functional record is truncated or corrupt (checksum mismatch)");
  Reader r(name, bytes + head, size - head - tail);
  FunctionalRecord rec;
  fields(r, rec);
  if (r.at() != size - head - tail) r.fail("bytes after the record's end");
  rec.m_mapping = file;
  rec.m_bytes = bytes + head;
  rec.m_file = name;
  return rec;
}

const RecordedTile& FunctionalRecord::tile(uint32_t segment, uint32_t i, RecordedTile& scratch) const {
  const RecordedSegment& s = segments.at(segment);
  if (s.encoded.empty()) return s.results.at(i);
  const auto [offset, bytes] = s.encoded.at(i);
  Reader r(m_file, m_bytes + offset, size_t(bytes));
  scratch.tris.clear();  // decoded into elements made anew (the fields not recorded at their defaults)
  fields(r, scratch);
  if (r.at() != bytes) r.fail("bytes after a tile's end");
  return scratch;
}

}  // namespace tilevis::sim
