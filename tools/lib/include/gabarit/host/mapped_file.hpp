// A read-only memory map of a whole file (the way a Linux board loads a table:
// no copy, pages shared with the page cache).
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace gabarit::host {

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

std::vector<std::byte> read_file(const std::string& path);
void write_file(const std::string& path, std::span<const std::byte> bytes);

}  // namespace gabarit::host
