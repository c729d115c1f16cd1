#include "gabarit/app/files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "gabarit/app/args.hpp"
#include "gabarit/app/error.hpp"
#include "gabarit/byte_order.hpp"
#include "gabarit/table_format.hpp"

namespace gabarit::app {
namespace {

struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

// Reads exactly n bytes (fewer at the end of the file): the count read.
std::size_t read_up_to(int fd, std::byte* out, std::size_t n, const std::string& path) {
  std::size_t done = 0;
  while (done < n) {
    const ssize_t r = ::read(fd, out + done, n - done);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) throw Error(path + ": read failed: " + std::strerror(errno));
    if (r == 0) break;
    done += static_cast<std::size_t>(r);
  }
  return done;
}

int open_input(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error(path + ": cannot open: " + std::strerror(errno));
  return fd;
}

}  // namespace

std::vector<std::byte> read_file(const std::string& path, std::size_t max_bytes) {
  Fd f{open_input(path)};
  struct stat st {};
  if (::fstat(f.fd, &st) != 0) throw Error(path + ": cannot stat: " + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) throw Error(path + ": is a directory");
  std::vector<std::byte> out;
  if (S_ISREG(st.st_mode)) {
    if (static_cast<std::uint64_t>(st.st_size) > max_bytes) {
      throw Error(path + ": " + std::to_string(st.st_size) + " bytes, more than the " + std::to_string(max_bytes) + " allowed");
    }
    out.resize(static_cast<std::size_t>(st.st_size));
    out.resize(read_up_to(f.fd, out.data(), out.size(), path));
    return out;
  }
  // A pipe or a device: in chunks, up to the limit.
  std::byte chunk[65536];
  for (;;) {
    const std::size_t n = read_up_to(f.fd, chunk, sizeof chunk, path);
    if (out.size() + n > max_bytes) throw Error(path + ": more than the " + std::to_string(max_bytes) + " bytes allowed");
    out.insert(out.end(), chunk, chunk + n);
    if (n < sizeof chunk) return out;
  }
}

std::string read_text(const std::string& path, std::size_t max_bytes) {
  const std::vector<std::byte> bytes = read_file(path, max_bytes);
  return std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size());
}

TableFile::TableFile(const std::string& path) {
  namespace tf = table_format;
  Fd f{open_input(path)};
  struct stat st {};
  if (::fstat(f.fd, &st) != 0 || !S_ISREG(st.st_mode)) throw Error(path + ": not a regular file");
  const auto file_size = static_cast<std::uint64_t>(st.st_size);
  // The header first: a file that is not a table, or whose declared size is
  // not the file's, is refused before anything large is read or checksummed.
  std::byte header[tf::kHeaderBytes] = {};
  const std::size_t got = read_up_to(f.fd, header, sizeof header, path);
  TableView probe;
  if (got < sizeof header || load_le<std::uint32_t>(header + tf::offset::kFileBytes) != file_size) {
    const Status s = TableView::open(std::span<const std::byte>(header, got), probe);
    throw Error(path + ": not a valid table: " + status_name(s == Status::kOk ? Status::kSizeMismatch : s));
  }
  size_ = static_cast<std::size_t>(file_size);
  words_.resize((size_ + 7) / 8);
  auto* bytes = reinterpret_cast<std::byte*>(words_.data());
  std::memcpy(bytes, header, sizeof header);
  if (read_up_to(f.fd, bytes + sizeof header, size_ - sizeof header, path) != size_ - sizeof header) {
    throw Error(path + ": not a valid table: " + status_name(Status::kTruncated) + " (the file changed while being read)");
  }
  if (const Status s = TableView::open(this->bytes(), view_); s != Status::kOk) {
    throw Error(path + ": not a valid table: " + status_name(s));
  }
}

OutputFile::OutputFile(std::string path) : path_(std::move(path)) {
  // An existing output that is not a regular file (/dev/null, a FIFO, a
  // terminal) is written through: renaming a temporary over it would
  // replace the device or pipe with a regular file.
  struct stat st {};
  if (::stat(path_.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    if (S_ISDIR(st.st_mode)) throw Error(path_ + ": cannot create: is a directory");
    file_ = std::fopen(path_.c_str(), "wb");
    if (file_ == nullptr) throw Error(path_ + ": cannot create: " + std::strerror(errno));
    direct_ = true;
    return;
  }
  const std::filesystem::path target(path_);
  const std::string dir = target.has_parent_path() ? target.parent_path().string() : std::string(".");
  std::string name = dir + "/." + target.filename().string() + ".tmp.XXXXXX";
  const int fd = ::mkstemp(name.data());
  if (fd < 0) throw Error(path_ + ": cannot create: " + std::strerror(errno));
  // mkstemp makes the file 0600; give it what a plain create would (0666 less the umask).
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  file_ = ::fdopen(fd, "wb");
  if (file_ == nullptr) {
    ::close(fd);
    ::unlink(name.c_str());
    throw Error(path_ + ": cannot create: " + std::strerror(errno));
  }
  temporary_ = name;
}

OutputFile::~OutputFile() { discard(); }

void OutputFile::discard() noexcept {
  if (file_ != nullptr) std::fclose(file_);
  file_ = nullptr;
  if (!temporary_.empty()) ::unlink(temporary_.c_str());
  temporary_.clear();
}

void OutputFile::write(std::string_view text) {
  if (file_ == nullptr) throw Error(path_ + ": write after commit");
  if (std::fwrite(text.data(), 1, text.size(), file_) != text.size()) failed_ = true;
}

void OutputFile::write(std::span<const std::byte> bytes) {
  write(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

void OutputFile::commit() {
  if (file_ == nullptr) throw Error(path_ + ": committed twice");
  if (direct_) {
    const bool ok = std::fflush(file_) == 0;
    const int e = errno;
    const bool closed = std::fclose(file_) == 0;
    file_ = nullptr;
    if (failed_ || !ok || !closed) throw Error(path_ + ": write failed: " + std::strerror(e != 0 ? e : EIO));
    return;
  }
  const bool flushed = std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
  const int flush_errno = errno;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (failed_ || !flushed || !closed) {
    discard();
    throw Error(path_ + ": write failed: " + std::strerror(flush_errno != 0 ? flush_errno : EIO));
  }
  if (::rename(temporary_.c_str(), path_.c_str()) != 0) {
    const int e = errno;
    discard();
    throw Error(path_ + ": cannot replace: " + std::strerror(e));
  }
  temporary_.clear();
}

void write_file(const std::string& path, std::span<const std::byte> bytes) {
  OutputFile out(path);
  out.write(bytes);
  out.commit();
}

void write_file(const std::string& path, std::string_view text) {
  OutputFile out(path);
  out.write(text);
  out.commit();
}

namespace {

bool same_file(const std::string& a, std::string_view b) {
  struct stat sa {}, sb {};
  const std::string bs(b);
  if (::stat(a.c_str(), &sa) == 0 && ::stat(bs.c_str(), &sb) == 0) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  std::error_code ec;
  const auto ca = std::filesystem::weakly_canonical(a, ec);
  const auto cb = std::filesystem::weakly_canonical(bs, ec);
  return !ec && ca == cb;
}

}  // namespace

void refuse_same_file(const std::string& output, const char* option, std::initializer_list<std::string_view> inputs) {
  for (std::string_view input : inputs) {
    if (!input.empty() && same_file(output, input)) {
      throw UsageError(std::string(option) + " " + output + " is also an input (" + std::string(input) + "); refusing to overwrite it");
    }
  }
}

void refuse_same_file(const std::string& output, const char* option, const std::vector<std::string>& inputs) {
  for (const std::string& input : inputs) refuse_same_file(output, option, {input});
}

}  // namespace gabarit::app
