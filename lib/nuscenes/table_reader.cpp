// stream_table: the file (size limit, mmap) and the error prefix around the scanner
// (table_scanner.cpp).
#include "nuscenes/table_reader.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/bounded_read.hpp"
#include "nuscenes/table_scanner.hpp"

namespace faultline::nuscenes {
namespace {

// Read-only view of a whole file, mapped when possible.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) return;
    struct stat st {};
    if (::fstat(fd_, &st) != 0) return;
    size_ = static_cast<std::size_t>(st.st_size);
    opened_ = true;
    if (size_ == 0) return;
    void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd_, 0);
    if (p == MAP_FAILED) {
      opened_ = false;
      return;
    }
    ::madvise(p, size_, MADV_SEQUENTIAL);
    data_ = static_cast<const char*>(p);
  }
  ~MappedFile() {
    if (data_) ::munmap(const_cast<char*>(data_), size_);
    if (fd_ >= 0) ::close(fd_);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  bool opened() const { return opened_; }
  const char* data() const { return data_; }
  std::size_t size() const { return size_; }

 private:
  int fd_ = -1;
  bool opened_ = false;
  const char* data_ = nullptr;
  std::size_t size_ = 0;
};

// The scan with `name` (the path) prefixing every error.
Status scan_table(std::string_view bytes, bool release, const std::string& name,
                  const std::vector<std::string>& wanted, const RecordFn& on_record,
                  const RecordFilter& filter) {
  detail::ScanError error;
  Status s = detail::scan_records(bytes, release, wanted, on_record, filter, error);
  if (s.is_ok()) return s;
  if (!error.parse_failed) return Status(s.code(), name + ": " + s.message());
  if (error.truncated) {
    return Status(StatusCode::kTruncated, name + ": malformed JSON at offset " +
                                              std::to_string(error.offset) + ": " + s.message() +
                                              " (the table ends early: truncated?)");
  }
  return Status(StatusCode::kCorruptData, name + ": malformed JSON at offset " +
                                              std::to_string(error.offset) + ": " + s.message());
}

}  // namespace

bool TableField::get(std::string* out) const {
  if (kind != FieldKind::kString) return false;
  *out = str;
  return true;
}

bool TableField::get(std::int64_t* out) const {
  if (kind != FieldKind::kNumber || !is_integer) return false;
  *out = integer;
  return true;
}

bool TableField::get(bool* out) const {
  if (kind != FieldKind::kBool) return false;
  *out = boolean;
  return true;
}

bool TableField::get_numbers(std::vector<double>* out) const {
  if (kind != FieldKind::kList || !strs.empty()) return false;
  *out = nums;
  return true;
}

Status stream_table(const std::string& path, const std::vector<std::string>& wanted,
                    const RecordFn& on_record, const RecordFilter& filter) {
  if (Status size = check_file_size(path, kMaxNuScenesTableBytes, "nuScenes table"); !size)
    return size;
  MappedFile file(path);
  if (!file.opened()) return Status(StatusCode::kNotFound, path + ": table not found");
  const std::string_view bytes =
      file.data() ? std::string_view(file.data(), file.size()) : std::string_view("");
  return scan_table(bytes, file.data() != nullptr, path, wanted, on_record, filter);
}

Status stream_table_bytes(std::string_view bytes, const std::string& name,
                          const std::vector<std::string>& wanted, const RecordFn& on_record,
                          const RecordFilter& filter) {
  return scan_table(bytes.empty() ? std::string_view("") : bytes, false, name, wanted, on_record,
                    filter);
}

}  // namespace faultline::nuscenes
