// Linear MCAP reading, record by record from the leading magic. Every length read from the file is
// checked against what is left before it is used, so truncated or hostile input ends in a Problem,
// not a crash. (Indexed reading: reader_index.cpp; chunk decoding: reader_records.cpp.)
#include "bag/reader.hpp"

#include "bag/reader_records.hpp"

namespace faultline::bag {

std::string Problem::to_string() const {
  return "offset " + std::to_string(offset) + ": " + message;
}

namespace {

using reader_detail::decode_chunk_view;
using reader_detail::for_each_inner_record;
using reader_detail::hex32;
using reader_detail::InnerRecord;
using reader_detail::Tables;
using reader_detail::time_selected;
using reader_detail::topic_selected;

// One pass over the records in file order: the state of Reader::read_linear.
class LinearScanner {
 public:
  LinearScanner(IReadable& source, const ReadOptions& options, const MessageCallback& on_message,
                const ProblemCallback& on_problem)
      : source_(source), options_(options), on_message_(on_message), on_problem_(on_problem) {
    scan_.file_bytes = source_.size();
    size_ = scan_.file_bytes;
  }

  // Checks the leading magic; non-ok when nothing can be read.
  Status start() {
    std::string buf;
    if (scan_.file_bytes < kMagic.size()) {
      return Status(StatusCode::kTruncated, "file of " + std::to_string(scan_.file_bytes) +
                                                " bytes is too short for the MCAP magic");
    }
    if (Status s = source_.read(0, kMagic.size(), buf); !s) return s;
    if (buf != kMagic)
      return Status(StatusCode::kCorruptData, "offset 0: not an MCAP file (bad magic)");
    data_crc_ = crc32_update(0, buf);
    pos_ = kMagic.size();
    scan_.valid_end = pos_;
    return Status::ok();
  }

  // Starts from the summary's schemas and channels (a message may precede its channel record).
  void use_tables(const Summary& summary) {
    tables_.schemas = summary.schemas;
    tables_.channels = summary.channels;
  }

  Result<LinearScan> run() {
    while (true) {
      auto step = next_record();
      if (!step) return step.status();
      if (*step == Step::kEnd) break;
      if (*step == Step::kStop) {
        scan_.stopped_early = !scan_.footer_found;
        break;
      }
    }
    if (scan_.footer_found && !scan_.data_end_offset) {
      report({scan_.valid_end, StatusCode::kCorruptData, "no DataEnd record before the Footer"});
    }
    return scan_;
  }

 private:
  enum class Step {
    kNext,  // go on with the record at pos_
    kStop,  // stop after the record just read (footer, or the callback said so)
    kEnd,   // the file ends (or cannot be followed) at pos_
  };

  void report(const Problem& p) {
    scan_.problems++;
    if (on_problem_) on_problem_(p);
  }

  bool selected(const MessageView& view) const {
    return topic_selected(options_, *view.channel) &&
           time_selected(options_, static_cast<std::uint64_t>(view.log_time_ns));
  }

  // Reads the record at pos_ and acts on it.
  Result<Step> next_record() {
    if (pos_ == size_) {
      report({pos_, StatusCode::kTruncated,
              "file ends without a Footer (writer did not close; try `faultline bag recover`)"});
      return Step::kEnd;
    }
    if (size_ - pos_ < kRecordPrefixBytes) {
      report({pos_, StatusCode::kTruncated,
              "truncated record header (" + std::to_string(size_ - pos_) + " bytes left)"});
      return Step::kEnd;
    }
    std::string prefix;
    if (Status s = source_.read(pos_, kRecordPrefixBytes, prefix); !s) return s;
    ByteReader pr(prefix);
    std::uint8_t op = 0;
    std::uint64_t len = 0;
    (void)pr.u8(op);
    (void)pr.u64(len);
    const std::uint64_t left = size_ - pos_ - kRecordPrefixBytes;
    if (len > left) {
      report({pos_, StatusCode::kTruncated,
              std::string(opcode_name(op)) + " record (opcode 0x" + hex32(op).substr(6) +
                  ") declares " + std::to_string(len) + " content bytes but only " +
                  std::to_string(left) + " remain"});
      return Step::kEnd;
    }
    const std::uint64_t next = pos_ + kRecordPrefixBytes + len;
    if (op == 0)
      report({pos_, StatusCode::kCorruptData, "invalid opcode 0x00 (skipped by length)"});
    if (first_ && op != static_cast<std::uint8_t>(Opcode::kHeader)) {
      report({pos_, StatusCode::kCorruptData, "first record is not a Header"});
    }
    first_ = false;

    const auto opcode = static_cast<Opcode>(op);
    const bool crc_on = options_.verify_data_crc;
    const bool needed = opcode == Opcode::kChunk || opcode == Opcode::kSchema ||
                        opcode == Opcode::kChannel || opcode == Opcode::kMessage ||
                        opcode == Opcode::kFooter || opcode == Opcode::kDataEnd ||
                        opcode == Opcode::kHeader || opcode == Opcode::kMetadata ||
                        static_cast<bool>(options_.on_record) || (crc_on && !scan_.data_end_offset);
    if (len > options_.max_record_bytes) {
      report({pos_, StatusCode::kCorruptData,
              std::string(opcode_name(op)) + " record of " + std::to_string(len) +
                  " bytes exceeds the limit of " + std::to_string(options_.max_record_bytes) +
                  " (skipped)"});
      pos_ = next;
      return Step::kNext;
    }
    content_.clear();
    if (needed) {
      if (Status s = source_.read(pos_ + kRecordPrefixBytes, len, content_); !s) return s;
    }
    if (crc_on && !scan_.data_end_offset && opcode != Opcode::kDataEnd) {
      data_crc_ = crc32_update(data_crc_, prefix);
      data_crc_ = crc32_update(data_crc_, content_);
    }
    if (options_.on_record) options_.on_record(RecordView{pos_, op, len, content_});

    const bool stop = dispatch(opcode, next);
    pos_ = next;
    scan_.valid_end = pos_;
    return stop ? Step::kStop : Step::kNext;
  }

  // Acts on the record at pos_ (content_ read); true to stop after it.
  bool dispatch(Opcode opcode, std::uint64_t next) {
    switch (opcode) {
      case Opcode::kSchema:
        tables_.add_schema(content_, pos_, report_fn_);
        return false;
      case Opcode::kChannel:
        tables_.add_channel(content_, pos_, report_fn_);
        return false;
      case Opcode::kMessage: {
        MessageView view;
        if (tables_.make_view(content_, pos_, report_fn_, view) && selected(view)) {
          view.record_offset = pos_;
          scan_.messages++;
          if (on_message_ && !on_message_(view)) return true;
        }
        return false;
      }
      case Opcode::kChunk:
        return on_chunk(next);
      case Opcode::kMessageIndex:
        if (scan_.last_chunk_end == pos_)
          scan_.last_chunk_end = next;  // belongs to the chunk before
        return false;
      case Opcode::kDataEnd:
        on_data_end();
        return false;
      case Opcode::kFooter:
        on_footer(next);
        return true;
      default:
        return false;  // Header, Metadata, summary records, unknown opcodes: skipped by length
    }
  }

  // The records of the Chunk at pos_; true when the message callback asked to stop.
  bool on_chunk(std::uint64_t next) {
    ChunkHeader header;
    std::string_view chunk_records;
    if (Status s =
            decode_chunk_view(content_, options_.max_record_bytes, header, records_, chunk_records);
        !s) {
      scan_.bad_chunks++;
      report({pos_, s.code(), s.message()});
      return false;
    }
    bool stop = false;
    std::uint64_t bad = 0;
    const bool ok = for_each_inner_record(chunk_records, bad, [&](const InnerRecord& r) {
      const std::uint64_t at = pos_;  // problems inside a chunk name the chunk's offset
      switch (static_cast<Opcode>(r.opcode)) {
        case Opcode::kSchema:
          tables_.add_schema(r.content, at, report_fn_);
          break;
        case Opcode::kChannel:
          tables_.add_channel(r.content, at, report_fn_);
          break;
        case Opcode::kMessage: {
          MessageView view;
          if (tables_.make_view(r.content, at, report_fn_, view) && selected(view)) {
            view.chunk_offset = pos_;
            view.record_offset = r.offset;
            scan_.messages++;
            if (on_message_ && !on_message_(view)) {
              stop = true;
              return false;
            }
          }
          break;
        }
        default:
          report({at, StatusCode::kCorruptData,
                  std::string("unexpected ") + opcode_name(r.opcode) +
                      " record inside a Chunk at +" + std::to_string(r.offset)});
      }
      return true;
    });
    if (!ok) {
      scan_.bad_chunks++;
      report({pos_, StatusCode::kCorruptData,
              "Chunk record at +" + std::to_string(bad) + " overruns the chunk"});
      return stop;
    }
    scan_.chunks++;
    scan_.last_chunk_end = next;
    return stop;
  }

  void on_data_end() {
    ByteReader r(content_);
    std::uint32_t stored = 0;
    if (!r.u32(stored)) {
      report({pos_, StatusCode::kCorruptData, "malformed DataEnd record"});
      return;
    }
    scan_.data_end_offset = pos_;
    scan_.data_crc_stored = stored;
    if (options_.verify_data_crc) {
      scan_.data_crc_computed = data_crc_;
      if (stored != 0 && stored != data_crc_) {
        report({pos_, StatusCode::kCorruptData,
                "data section CRC mismatch: stored " + hex32(stored) + ", computed " +
                    hex32(data_crc_)});
      }
    }
  }

  void on_footer(std::uint64_t next) {
    scan_.footer_found = true;
    std::string tail;
    if (size_ - next < kMagic.size() || !source_.read(next, kMagic.size(), tail) ||
        tail != kMagic) {
      report({next, StatusCode::kCorruptData, "Footer is not followed by the closing magic"});
    } else if (size_ - next > kMagic.size()) {
      report({next + kMagic.size(), StatusCode::kCorruptData,
              std::to_string(size_ - next - kMagic.size()) + " bytes after the closing magic"});
    }
  }

  IReadable& source_;
  const ReadOptions& options_;
  const MessageCallback& on_message_;
  const ProblemCallback& on_problem_;
  LinearScan scan_;
  const ProblemCallback report_fn_ = [this](const Problem& p) { report(p); };
  std::uint64_t size_ = 0;
  std::uint64_t pos_ = 0;
  bool first_ = true;
  std::uint32_t data_crc_ = 0;
  Tables tables_;
  std::string content_, records_;
};

}  // namespace

Result<std::unique_ptr<Reader>> Reader::open(const std::string& path) {
  auto src = FileSource::open(path);
  if (!src) return src.status();
  return std::unique_ptr<Reader>(new Reader(std::move(src).value()));
}

std::unique_ptr<Reader> Reader::open(std::unique_ptr<IReadable> source) {
  return std::unique_ptr<Reader>(new Reader(std::move(source)));
}

Result<LinearScan> Reader::read_linear(const ReadOptions& options,
                                       const MessageCallback& on_message,
                                       const ProblemCallback& on_problem) {
  LinearScanner scanner(*source_, options, on_message, on_problem);
  if (Status s = scanner.start(); !s) return s;
  if (options.use_summary_tables && load_summary().is_ok()) scanner.use_tables(summary_);
  return scanner.run();
}

}  // namespace faultline::bag
