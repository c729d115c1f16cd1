// A read-only memory map of a whole file (the way a Linux board loads a table:
// no copy, pages shared with the page cache).
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "gabarit/table_view.hpp"

namespace gabarit::app {

class MappedFile {
 public:
  explicit MappedFile(const std::string& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  std::span<const std::byte> bytes() const { return {static_cast<const std::byte*>(data_), size_}; }

 private:
  void* data_ = nullptr;
  std::size_t size_ = 0;
};

// A table file mapped and validated once (TableView::open); the view points
// into the mapping, so the object is neither copied nor moved. Throws
// app::Error "PATH: not a valid table: STATUS".
class TableFile {
 public:
  explicit TableFile(const std::string& path);
  TableFile(const TableFile&) = delete;
  TableFile& operator=(const TableFile&) = delete;
  const TableView& view() const { return view_; }
  std::span<const std::byte> bytes() const { return file_.bytes(); }

 private:
  MappedFile file_;
  TableView view_;
};

std::vector<std::byte> read_file(const std::string& path);
void write_file(const std::string& path, std::span<const std::byte> bytes);

}  // namespace gabarit::app
