#include "s2c/core/files.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>

#include <openssl/evp.h>
#include <fmt/format.h>

#include "s2c/core/errors.h"

namespace fs = std::filesystem;

namespace s2c {
namespace {

std::string random_tag() {
  std::random_device rd;
  return fmt::format("{:08x}", rd());
}

void fsync_path(const fs::path& p) {
  int fd = ::open(p.c_str(), O_RDONLY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

std::string hex(const unsigned char* d, unsigned n) {
  std::string s;
  s.reserve(2 * n);
  for (unsigned i = 0; i < n; ++i) s += fmt::format("{:02x}", d[i]);
  return s;
}

struct Sha256 {
  EVP_MD_CTX* ctx = EVP_MD_CTX_new();
  Sha256() { EVP_DigestInit_ex(ctx, EVP_sha256(), nullptr); }
  ~Sha256() { EVP_MD_CTX_free(ctx); }
  void update(const void* data, std::size_t n) { EVP_DigestUpdate(ctx, data, n); }
  std::string finish() {
    unsigned char digest[EVP_MAX_MD_SIZE];
    unsigned n = 0;
    EVP_DigestFinal_ex(ctx, digest, &n);
    return hex(digest, n);
  }
};

}  // namespace

AtomicFile::AtomicFile(fs::path target) : target_(std::move(target)) {
  fs::path dir = target_.parent_path();
  if (!dir.empty() && !fs::is_directory(dir)) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw IoError(fmt::format("{}: cannot create folder: {}", dir.string(), ec.message()));
  }
  // ".name.tmp-XXXX.ext": hidden, unique, and with the extension writers dispatch on.
  temp_ = dir / fmt::format(".{}.tmp-{}{}", target_.stem().string(), random_tag(),
                            target_.extension().string());
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    std::error_code ec;
    fs::remove(temp_, ec);
  }
}

void AtomicFile::commit() {
  if (!fs::exists(temp_)) throw IoError(fmt::format("{}: nothing was written", target_.string()));
  fsync_path(temp_);
  std::error_code ec;
  fs::rename(temp_, target_, ec);
  if (ec) throw IoError(fmt::format("{}: cannot move output into place: {}", target_.string(), ec.message()));
  committed_ = true;
  fs::path dir = target_.parent_path();
  fsync_path(dir.empty() ? fs::path(".") : dir);
}

AtomicStream::AtomicStream(fs::path target) : file_(std::move(target)) {
  fd_ = ::open(file_.temp_path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw IoError(fmt::format("{}: cannot write: {}", file_.target().string(), std::strerror(errno)));
}

AtomicStream::~AtomicStream() { close_file(); }

void AtomicStream::close_file() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void AtomicStream::write(std::string_view piece) {
  // Writeback in steps of this many bytes: large enough for few calls, small enough that the
  // disk works while the rest is printed.
  constexpr std::uint64_t kFlushStep = 4 << 20;
  while (!piece.empty()) {
    const ssize_t n = ::write(fd_, piece.data(), piece.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw IoError(fmt::format("{}: write failed: {}", file_.target().string(), std::strerror(errno)));
    piece.remove_prefix(static_cast<std::size_t>(n));
    written_ += static_cast<std::uint64_t>(n);
  }
  if (written_ - flushed_ >= kFlushStep) {
    // Only a hint: where the file system does not take it, commit's fsync does all the work.
    ::sync_file_range(fd_, static_cast<off_t>(flushed_), static_cast<off_t>(written_ - flushed_), SYNC_FILE_RANGE_WRITE);
    flushed_ = written_;
  }
}

void AtomicStream::commit() {
  const bool synced = ::fsync(fd_) == 0;
  const int saved = errno;
  close_file();
  if (!synced && saved != EINVAL && saved != EROFS)  // (the two for files that cannot be synced)
    throw IoError(fmt::format("{}: write failed: {}", file_.target().string(), std::strerror(saved)));
  file_.commit();
}

void write_file_atomic(const fs::path& path, const std::string& content) {
  AtomicStream out(path);
  out.write(content);
  out.commit();
}

std::string read_file(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw IoError(fmt::format("{}: cannot open: {}", path.string(), std::strerror(errno)));
  std::ostringstream ss;
  ss << f.rdbuf();
  if (f.bad()) throw IoError(fmt::format("{}: read failed", path.string()));
  return ss.str();
}

void refuse_same_file(const fs::path& input, const fs::path& output) {
  std::error_code ec;
  if (fs::exists(output, ec) && fs::equivalent(input, output, ec))
    throw InvalidInput(fmt::format("{}: output would overwrite the input; choose another output path",
                                   output.string()));
}

std::string sha256_file(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw IoError(fmt::format("{}: cannot open for hashing: {}", path.string(), std::strerror(errno)));
  Sha256 h;
  std::vector<char> buf(1 << 16);
  while (f) {
    f.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    h.update(buf.data(), static_cast<std::size_t>(f.gcount()));
  }
  return h.finish();
}

std::string sha256_bytes(const std::string& bytes) {
  Sha256 h;
  h.update(bytes.data(), bytes.size());
  return h.finish();
}

}  // namespace s2c
