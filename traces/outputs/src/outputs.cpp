#include "tilevis/outputs.h"

#include <cstring>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfThreading.h>
#include <thread>

#include "tilevis/fnv1a.h"

namespace tilevis::outputs {
namespace fs = std::filesystem;

size_t TileTable::column(const std::string& name) const {
  for (size_t i = 0; i < columns.size(); ++i)
    if (columns[i] == name) return i;
  return std::string::npos;
}

void TileTable::resize(uint32_t tw, uint32_t th, uint32_t width, uint32_t height, std::vector<std::string> names) {
  tile_w = tw;
  tile_h = th;
  tiles_x = (width + tw - 1) / tw;
  tiles_y = (height + th - 1) / th;
  columns = std::move(names);
  rows.assign(size_t(tiles_x) * tiles_y, std::vector<int64_t>(columns.size(), 0));
}

namespace {

[[noreturn]] void fail(const fs::path& file, const std::string& what) {
  throw std::runtime_error(file.string() + ": " + what);
}

// Writes via a temporary file and a rename, so no reader sees half a file.
template <typename WriteFn>
void atomic_write(const fs::path& file, WriteFn&& write) {
  fs::path tmp = file;
  tmp += ".tmp";
  write(tmp);
  fs::rename(tmp, file);
}

std::string id_channel(uint32_t s, uint32_t samples) {
  return samples == 1 ? "id" : "id.s" + std::to_string(s);
}

void write_ids(const Result& r, const fs::path& file) {
  atomic_write(file, [&](const fs::path& tmp) {
    Imf::Header header(int(r.width), int(r.height));
    header.compression() = Imf::ZIP_COMPRESSION;
    header.zipCompressionLevel() = 1;
    for (uint32_t s = 0; s < r.samples; ++s) header.channels().insert(id_channel(s, r.samples), Imf::Channel(Imf::UINT));
    Imf::FrameBuffer fb;
    const size_t xs = sizeof(int32_t) * r.samples, ys = xs * r.width;
    for (uint32_t s = 0; s < r.samples; ++s)
      fb.insert(id_channel(s, r.samples),
                Imf::Slice(Imf::UINT, reinterpret_cast<char*>(const_cast<int32_t*>(r.ids.data()) + s), xs, ys));
    Imf::OutputFile out(tmp.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(int(r.height));
  });
}

void write_overdraw(const Result& r, const fs::path& file) {
  atomic_write(file, [&](const fs::path& tmp) {
    Imf::Header header(int(r.width), int(r.height));
    header.compression() = Imf::ZIP_COMPRESSION;
    header.channels().insert("overdraw", Imf::Channel(Imf::FLOAT));
    Imf::FrameBuffer fb;
    fb.insert("overdraw", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(r.overdraw.data())),
                                     sizeof(float), sizeof(float) * r.width));
    Imf::OutputFile out(tmp.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(int(r.height));
  });
}

constexpr char kAreaMagic[8] = {'T', 'V', 'A', 'R', 'E', 'A', '0', '1'};

void write_areas(const std::vector<double>& areas, const fs::path& file) {
  atomic_write(file, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    uint64_t n = areas.size();
    out.write(kAreaMagic, sizeof kAreaMagic);
    out.write(reinterpret_cast<const char*>(&n), sizeof n);
    out.write(reinterpret_cast<const char*>(areas.data()), std::streamsize(n * sizeof(double)));
    if (!out) fail(tmp, "write failed");
  });
}

void write_tiles(const TileTable& t, const fs::path& file) {
  atomic_write(file, [&](const fs::path& tmp) {
    std::ofstream out(tmp);
    out << "tx,ty,x0,y0";
    for (const auto& c : t.columns) out << ',' << c;
    out << '\n';
    for (uint32_t ty = 0; ty < t.tiles_y; ++ty)
      for (uint32_t tx = 0; tx < t.tiles_x; ++tx) {
        out << tx << ',' << ty << ',' << tx * t.tile_w << ',' << ty * t.tile_h;
        for (int64_t v : t.rows[size_t(ty) * t.tiles_x + tx]) out << ',' << v;
        out << '\n';
      }
    if (!out) fail(tmp, "write failed");
  });
}

void read_ids(Result& r, const fs::path& file) {
  Imf::InputFile in(file.c_str());
  const auto& dw = in.header().dataWindow();
  r.width = uint32_t(dw.max.x - dw.min.x + 1);
  r.height = uint32_t(dw.max.y - dw.min.y + 1);
  uint32_t samples = 0;
  for (auto it = in.header().channels().begin(); it != in.header().channels().end(); ++it) ++samples;
  if (samples == 0 || samples > 16) fail(file, "expected 1 to 16 id channels");
  r.samples = samples;
  r.ids.assign(size_t(r.width) * r.height * samples, kBackground);
  Imf::FrameBuffer fb;
  const size_t xs = sizeof(int32_t) * samples, ys = xs * r.width;
  for (uint32_t s = 0; s < samples; ++s) {
    std::string name = id_channel(s, samples);
    if (!in.header().channels().findChannel(name)) fail(file, "missing channel " + name);
    fb.insert(name, Imf::Slice(Imf::UINT, reinterpret_cast<char*>(r.ids.data() + s), xs, ys));
  }
  in.setFrameBuffer(fb);
  in.readPixels(dw.min.y, dw.max.y);
}

std::vector<double> read_areas(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  char magic[8];
  uint64_t n = 0;
  if (!in.read(magic, 8) || std::memcmp(magic, kAreaMagic, 8) != 0) fail(file, "bad magic");
  if (!in.read(reinterpret_cast<char*>(&n), sizeof n)) fail(file, "truncated header");
  if (n != (fs::file_size(file) - 16) / sizeof(double) || (fs::file_size(file) - 16) % sizeof(double))
    fail(file, "count " + std::to_string(n) + " does not match the file size");
  std::vector<double> a(n);
  in.read(reinterpret_cast<char*>(a.data()), std::streamsize(n * sizeof(double)));
  return a;
}

TileTable read_tiles(const fs::path& file, uint32_t width, uint32_t height) {
  std::ifstream in(file);
  std::string line;
  if (!std::getline(in, line)) fail(file, "empty");
  std::vector<std::string> cols;
  std::stringstream hs(line);
  for (std::string c; std::getline(hs, c, ',');) cols.push_back(c);
  if (cols.size() < 4 || cols[0] != "tx" || cols[1] != "ty" || cols[2] != "x0" || cols[3] != "y0")
    fail(file, "expected header tx,ty,x0,y0,...");
  std::vector<std::vector<int64_t>> rows;
  uint32_t max_tx = 0, max_ty = 0, tw = 0, th = 0;
  size_t line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    std::vector<int64_t> v;
    std::stringstream ls(line);
    size_t field = 0;
    for (std::string c; std::getline(ls, c, ',');) {
      ++field;
      size_t used = 0;
      int64_t value = 0;
      try {
        value = std::stoll(c, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || used != c.size())
        fail(file, "line " + std::to_string(line_no) + ", field " + std::to_string(field) + " (" +
                       (field <= cols.size() ? cols[field - 1] : std::string("beyond the header")) + "): expected an "
                       "integer, got '" + c + "'");
      v.push_back(value);
    }
    if (v.size() != cols.size()) fail(file, "line " + std::to_string(line_no) + ": expected " + std::to_string(cols.size()) + " fields");
    max_tx = std::max(max_tx, uint32_t(v[0]));
    max_ty = std::max(max_ty, uint32_t(v[1]));
    if (v[0] == 1 && v[1] == 0) tw = uint32_t(v[2]);
    if (v[0] == 0 && v[1] == 1) th = uint32_t(v[3]);
    rows.push_back(std::vector<int64_t>(v.begin() + 4, v.end()));
  }
  TileTable t;
  t.tiles_x = max_tx + 1;
  t.tiles_y = max_ty + 1;
  t.tile_w = tw ? tw : width;
  t.tile_h = th ? th : height;
  if (rows.size() != size_t(t.tiles_x) * t.tiles_y) fail(file, "expected one row per tile");
  t.columns.assign(cols.begin() + 4, cols.end());
  t.rows = std::move(rows);
  return t;
}

}  // namespace

// FNV-1a 64 of a file's bytes, hex; empty if it cannot be read.
std::string file_fnv1a64(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return {};
  uint64_t h = kFnv1a64Basis;
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), std::streamsize(buf.size()));
    h = fnv1a64(buf.data(), size_t(in.gcount()), h);
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

void write_result(const Result& r, const fs::path& dir) {
  static const bool threads = [] { Imf::setGlobalThreadCount(int(std::thread::hardware_concurrency())); return true; }();
  (void)threads;
  // The trace's identity beside its name, so that compare can tell results of different traces apart.
  nlohmann::json stats = r.stats;
  if (stats.contains("trace") && stats["trace"].is_string() && !stats.contains("trace_fnv1a64"))
    if (const std::string h = file_fnv1a64(stats["trace"].get<std::string>()); !h.empty()) stats["trace_fnv1a64"] = h;
  fs::create_directories(dir);
  fs::remove(dir / "stats.json");  // its absence marks the directory as incomplete until the end
  if (!r.ids.empty()) {
    if (r.ids.size() != size_t(r.width) * r.height * r.samples) throw std::logic_error("ids size != width*height*samples");
    write_ids(r, dir / "ids.exr");
  }
  if (!r.overdraw.empty()) write_overdraw(r, dir / "overdraw.exr");
  if (!r.visible_area.empty()) write_areas(r.visible_area, dir / "visible_area.bin");
  if (!r.tiles.rows.empty()) write_tiles(r.tiles, dir / "tiles.csv");
  atomic_write(dir / "stats.json", [&](const fs::path& tmp) {
    std::ofstream out(tmp);
    out << stats.dump(2) << '\n';
    if (!out) fail(tmp, "write failed");
  });
}

Result read_result(const fs::path& dir) {
  Result r;
  fs::path stats = dir / "stats.json";
  std::ifstream in(stats);
  if (!in) fail(stats, "not found (not a complete result directory)");
  try {
    r.stats = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    fail(stats, e.what());
  }
  try {
    if (fs::exists(dir / "ids.exr")) read_ids(r, dir / "ids.exr");
  } catch (const std::exception& e) {
    fail(dir / "ids.exr", e.what());
  }
  if (fs::exists(dir / "visible_area.bin")) r.visible_area = read_areas(dir / "visible_area.bin");
  if (fs::exists(dir / "tiles.csv")) r.tiles = read_tiles(dir / "tiles.csv", r.width, r.height);
  return r;
}

}  // namespace tilevis::outputs
