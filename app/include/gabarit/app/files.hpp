// Files in and out for hosted programs.
//
// Inputs are read whole into memory the program owns. A table in particular
// is copied, not mapped: a table is validated once and then trusted by the
// voter's hot loop, and a mapping would let the file change under it (a
// rebuilt or truncated table gave SIGBUS, an in-place rewrite out-of-bounds
// counter writes). A copy costs the table's size in RAM once, which every
// board the project targets has; firmware reads its table from flash.
//
// Outputs never replace a file until they are complete: an OutputFile writes
// a temporary file beside the target, flushes and fsyncs it, and renames it
// over the target in commit(). A failed run (bad input, a full disk, an
// exception) leaves the previous file as it was.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "gabarit/table_view.hpp"

namespace gabarit::app {

// The whole of a regular file (or of a pipe, up to max_bytes). Throws
// app::Error "PATH: ..." when it cannot be read or is larger than max_bytes.
std::vector<std::byte> read_file(const std::string& path, std::size_t max_bytes = std::size_t{1} << 30);
// The same, as text (CSV, plans, maps): the one way host code opens a file to read.
std::string read_text(const std::string& path, std::size_t max_bytes = std::size_t{1} << 30);

// A table file read into owned, 8-byte-aligned memory and validated once
// (TableView::open). The header's size is checked against the file's before
// the rest is read, so a huge or foreign file is refused cheaply. Throws
// app::Error "PATH: not a valid table: STATUS".
class TableFile {
 public:
  explicit TableFile(const std::string& path);
  TableFile(const TableFile&) = delete;
  TableFile& operator=(const TableFile&) = delete;
  const TableView& view() const { return view_; }
  std::span<const std::byte> bytes() const {
    return {reinterpret_cast<const std::byte*>(words_.data()), size_};
  }

 private:
  std::vector<std::uint64_t> words_;
  std::size_t size_ = 0;
  TableView view_;
};

class OutputFile {
 public:
  // Creates the temporary beside `path`, or, when `path` exists and is not a
  // regular file (/dev/null, a FIFO), opens it to write through. Throws
  // app::Error "PATH: cannot create: ...".
  explicit OutputFile(std::string path);
  ~OutputFile();  // without commit(): the temporary is removed, `path` untouched
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  void write(std::string_view text);
  void write(std::span<const std::byte> bytes);
  std::FILE* stream() { return file_; }
  // Flushes, fsyncs and renames the temporary over `path`. Throws app::Error
  // "PATH: write failed: ..." (the temporary is then removed).
  void commit();
  const std::string& path() const { return path_; }

 private:
  void discard() noexcept;
  std::string path_, temporary_;
  std::FILE* file_ = nullptr;
  bool failed_ = false;
  bool direct_ = false;  // an existing non-regular file (a device, a FIFO): written through
};

// write_file: an OutputFile written and committed.
void write_file(const std::string& path, std::span<const std::byte> bytes);
void write_file(const std::string& path, std::string_view text);

// Throws app::UsageError "OPTION: OUTPUT is also an input (INPUT)" when
// `output` names the same file as one of `inputs` (the same device and
// inode, or the same path when the output does not exist yet).
void refuse_same_file(const std::string& output, const char* option, std::initializer_list<std::string_view> inputs);
void refuse_same_file(const std::string& output, const char* option, const std::vector<std::string>& inputs);

}  // namespace gabarit::app
