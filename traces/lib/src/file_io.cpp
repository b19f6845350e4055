#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <system_error>

#include "encode.h"
#include "tilevis/trace.h"

namespace tilevis::trace {

namespace {

struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using FileHandle = std::unique_ptr<std::FILE, FileCloser>;

[[noreturn]] void io_error(const std::string& path, const char* action, int error) {
  throw std::runtime_error(path + ": cannot " + action + ": " + std::generic_category().message(error));
}

}  // namespace

void write(const Trace& trace, const std::string& path) {
  validate(trace, path);
  const std::vector<uint8_t> bytes = detail::encode_valid(trace);
  const std::string temporary = path + ".tmp";
  {
    FileHandle file(std::fopen(temporary.c_str(), "wb"));
    if (!file) io_error(temporary, "create", errno);
    const size_t written = std::fwrite(bytes.data(), 1, bytes.size(), file.get());
    const int write_error = errno;
    // fclose flushes; a full disk may only show here.
    if (written != bytes.size() || std::fclose(file.release()) != 0) {
      const int error = written != bytes.size() ? write_error : errno;
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      io_error(temporary, "write", error);
    }
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw std::runtime_error(path + ": cannot rename " + temporary + " to it: " + ec.message());
  }
}

Trace read(const std::string& path) {
  FileHandle file(std::fopen(path.c_str(), "rb"));
  if (!file) io_error(path, "open", errno);
  std::vector<uint8_t> bytes;
  std::error_code ec;
  const auto size_hint = std::filesystem::file_size(path, ec);
  if (!ec) bytes.reserve(size_hint);
  uint8_t buffer[1 << 16];
  for (;;) {
    const size_t got = std::fread(buffer, 1, sizeof buffer, file.get());
    bytes.insert(bytes.end(), buffer, buffer + got);
    if (got < sizeof buffer) break;
  }
  if (std::ferror(file.get())) io_error(path, "read", errno);
  return decode(bytes.data(), bytes.size(), path);
}

}  // namespace tilevis::trace
