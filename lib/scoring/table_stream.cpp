// SAX handler for flat record arrays.
#include "scoring/table_stream.hpp"

#include <rapidjson/error/en.h>
#include <rapidjson/filereadstream.h>
#include <rapidjson/reader.h>

#include <cstdio>
#include <cstring>
#include <memory>

namespace faultline::scoring {
namespace {

class Handler : public rapidjson::BaseReaderHandler<rapidjson::UTF8<>, Handler> {
 public:
  Handler(const std::vector<std::string>& wanted,
          const std::function<Status(const TableRecord&, std::size_t)>& cb)
      : wanted_(wanted), cb_(cb) {
    rec_.fields.resize(wanted.size());
  }

  bool StartObject() {
    if (depth_ == 1) {
      for (auto& f : rec_.fields) {
        f.present = false;
        f.is_null = false;
        f.str.clear();
        f.nums.clear();
        f.strs.clear();
      }
      field_ = -1;
    } else if (depth_ == 0) {
      return fail("the table must be a JSON array of records, found an object");
    }
    ++depth_;
    return true;
  }
  bool EndObject(rapidjson::SizeType) {
    --depth_;
    if (depth_ == 1) {
      status_ = cb_(rec_, index_++);
      return status_.is_ok();
    }
    return true;
  }
  bool StartArray() {
    if (depth_ == 2 && field_ >= 0) rec_.fields[static_cast<std::size_t>(field_)].present = true;
    ++depth_;
    return true;
  }
  bool EndArray(rapidjson::SizeType) {
    --depth_;
    return true;
  }
  bool Key(const char* s, rapidjson::SizeType len, bool) {
    if (depth_ != 2) return true;
    field_ = -1;
    for (std::size_t i = 0; i < wanted_.size(); ++i) {
      if (wanted_[i].size() == len && std::memcmp(wanted_[i].data(), s, len) == 0) {
        field_ = static_cast<int>(i);
        break;
      }
    }
    return true;
  }
  bool String(const char* s, rapidjson::SizeType len, bool) {
    if (TableField* f = target()) {
      if (depth_ == 2) {
        f->str.assign(s, len);
      } else {
        f->strs.emplace_back(s, len);
      }
    }
    return true;
  }
  bool Num(double v) {
    if (TableField* f = target()) {
      if (depth_ == 2) {
        f->num = v;
      } else {
        f->nums.push_back(v);
      }
    }
    return true;
  }
  bool Int(int v) { return Num(v); }
  bool Uint(unsigned v) { return Num(v); }
  bool Int64(std::int64_t v) { return Num(static_cast<double>(v)); }
  bool Uint64(std::uint64_t v) { return Num(static_cast<double>(v)); }
  bool Double(double v) { return Num(v); }
  bool Bool(bool b) {
    if (TableField* f = target()) f->boolean = b;
    return true;
  }
  bool Null() {
    if (TableField* f = target()) f->is_null = true;
    return true;
  }
  bool Default() { return true; }

  const Status& status() const { return status_; }

 private:
  TableField* target() {
    if (depth_ < 2 || field_ < 0) return nullptr;
    auto* f = &rec_.fields[static_cast<std::size_t>(field_)];
    if (depth_ == 2) f->present = true;
    return f;
  }
  bool fail(const std::string& msg) {
    status_ = Status(StatusCode::kCorruptData, msg);
    return false;
  }

  const std::vector<std::string>& wanted_;
  const std::function<Status(const TableRecord&, std::size_t)>& cb_;
  TableRecord rec_;
  int depth_ = 0;
  int field_ = -1;
  std::size_t index_ = 0;
  Status status_;
};

}  // namespace

Status stream_table(const std::string& path, const std::vector<std::string>& wanted,
                    const std::function<Status(const TableRecord&, std::size_t)>& on_record) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> fp(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!fp) return Status(StatusCode::kNotFound, path + ": table not found");
  std::vector<char> buf(1 << 16);
  rapidjson::FileReadStream stream(fp.get(), buf.data(), buf.size());
  Handler handler(wanted, on_record);
  rapidjson::Reader reader;
  auto res = reader.Parse<rapidjson::kParseNanAndInfFlag | rapidjson::kParseFullPrecisionFlag>(stream,
                                                                                               handler);
  if (!handler.status().is_ok()) {
    return Status(handler.status().code(), path + ": " + handler.status().message());
  }
  if (res.IsError()) {
    return Status(StatusCode::kCorruptData, path + ": malformed JSON at offset " +
                                                std::to_string(res.Offset()) + ": " +
                                                rapidjson::GetParseError_En(res.Code()));
  }
  return Status::ok();
}

}  // namespace faultline::scoring
