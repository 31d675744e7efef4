// The table reader: decoded fields, skipped fields, Python's JSON extensions, errors with byte
// offsets.
#include "nuscenes/table_reader.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "test_util.hpp"

namespace faultline::nuscenes {
namespace {

using testing::TempDir;
using testing::write_text;

class TableReaderTest : public ::testing::Test {
 protected:
  // Scans `json` for the given fields; returns the status and keeps every record.
  Status scan(const std::string& json, const std::vector<std::string>& wanted) {
    const std::string path = dir_.file("table.json");
    write_text(path, json);
    records_.clear();
    return stream_table(path, wanted, [&](const TableRecord& r, std::size_t index) {
      EXPECT_EQ(index, records_.size());
      records_.push_back(r);
      return Status::ok();
    });
  }
  TempDir dir_{"table_reader"};
  std::vector<TableRecord> records_;
};

TEST_F(TableReaderTest, DecodesWantedFieldsAndSkipsTheRest) {
  const std::string json = R"([
{"token": "a1", "skip": {"nested": [1, {"x": "}"}]}, "translation": [1.5, -2e3, 0], "flag": true},
{"flag": false, "token": "b\"2\\", "translation": [], "extra": null}
])";
  ASSERT_TRUE(scan(json, {"token", "translation", "flag", "missing"}).is_ok());
  ASSERT_EQ(records_.size(), 2u);
  EXPECT_EQ(records_[0].fields[0].str, "a1");
  EXPECT_EQ(records_[0].fields[1].nums, (std::vector<double>{1.5, -2000.0, 0.0}));
  EXPECT_TRUE(records_[0].fields[2].boolean);
  EXPECT_FALSE(records_[0].fields[3].present);
  EXPECT_EQ(records_[1].fields[0].str, "b\"2\\");
  EXPECT_TRUE(records_[1].fields[1].present);
  EXPECT_TRUE(records_[1].fields[1].nums.empty());
  EXPECT_FALSE(records_[1].fields[2].boolean);
}

TEST_F(TableReaderTest, FlattensNestedListsAndKeepsStringLists) {
  const std::string json =
      R"([{"camera_intrinsic": [[1, 0, 2], [0, 3, 4], [0, 0, 1]], "attribute_tokens": ["x", "y"]}])";
  ASSERT_TRUE(scan(json, {"camera_intrinsic", "attribute_tokens"}).is_ok());
  ASSERT_EQ(records_.size(), 1u);
  EXPECT_EQ(records_[0].fields[0].nums, (std::vector<double>{1, 0, 2, 0, 3, 4, 0, 0, 1}));
  EXPECT_EQ(records_[0].fields[1].strs, (std::vector<std::string>{"x", "y"}));
}

TEST_F(TableReaderTest, ReadsPythonNanInfinityAndUnicodeEscapes) {
  const std::string json =
      R"([{"a": NaN, "b": -Infinity, "c": Infinity, "d": "\u00e9\ud83d\ude00", "e": null}])";
  ASSERT_TRUE(scan(json, {"a", "b", "c", "d", "e"}).is_ok());
  ASSERT_EQ(records_.size(), 1u);
  EXPECT_TRUE(std::isnan(records_[0].fields[0].num));
  EXPECT_EQ(records_[0].fields[1].num, -INFINITY);
  EXPECT_EQ(records_[0].fields[2].num, INFINITY);
  EXPECT_EQ(records_[0].fields[3].str, "\xc3\xa9\xf0\x9f\x98\x80");
  EXPECT_TRUE(records_[0].fields[4].is_null);
}

TEST_F(TableReaderTest, ParsesNumbersExactly) {
  const std::string json =
      R"([{"t": 1533151603547590, "x": 0.1, "y": 2.220446049250313e-16, "z": -0}])";
  ASSERT_TRUE(scan(json, {"t", "x", "y", "z"}).is_ok());
  EXPECT_EQ(records_[0].fields[0].num, 1533151603547590.0);
  EXPECT_EQ(records_[0].fields[1].num, 0.1);
  EXPECT_EQ(records_[0].fields[2].num, 2.220446049250313e-16);
  EXPECT_TRUE(std::signbit(records_[0].fields[3].num));
}

TEST_F(TableReaderTest, EmptyArrayHasNoRecords) {
  ASSERT_TRUE(scan(" [ ] \n", {"token"}).is_ok());
  EXPECT_TRUE(records_.empty());
}

TEST_F(TableReaderTest, ErrorsNameTheFileAndTheByteOffset) {
  struct Case {
    const char* json;
    std::size_t offset;
  };
  const Case cases[] = {
      {R"([{"token": "a"} {"token": "b"}])", 16},  // missing comma between records
      {R"([{"token": "a", "x": 01}])", 22},        // leading zero
      {R"([{"token": "a)", 11},                    // unterminated string
      {R"([{"token": tru}])", 11},                 // bad literal
      {R"([{"x": 1.}])", 9},                       // missing fraction
      {R"([{"x": 1}] trailing)", 11},              // garbage after the root
  };
  for (const Case& c : cases) {
    const Status s = scan(c.json, {"token", "x"});
    ASSERT_FALSE(s.is_ok()) << c.json;
    EXPECT_NE(s.message().find("table.json: malformed JSON at offset " + std::to_string(c.offset)),
              std::string::npos)
        << c.json << " -> " << s.message();
  }
}

TEST_F(TableReaderTest, RejectsAnObjectRootAndAMissingFile) {
  const Status s = scan(R"({"token": "a"})", {"token"});
  EXPECT_NE(s.message().find("must be a JSON array"), std::string::npos) << s.message();
  const Status missing = stream_table(dir_.file("nope.json"), {"token"},
                                      [](const TableRecord&, std::size_t) { return Status::ok(); });
  EXPECT_EQ(missing.code(), StatusCode::kNotFound);
  EXPECT_NE(missing.message().find("nope.json: table not found"), std::string::npos);
}

TEST_F(TableReaderTest, CallbackErrorStopsTheScan) {
  const std::string path = dir_.file("t.json");
  write_text(path, R"([{"token": "a"}, {"token": "b"}, {"token": "c"}])");
  int seen = 0;
  const Status s = stream_table(path, {"token"}, [&](const TableRecord& r, std::size_t) {
    ++seen;
    return r.fields[0].str == "b" ? Status(StatusCode::kInvalidArgument, "stop at b")
                                  : Status::ok();
  });
  EXPECT_EQ(seen, 2);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("t.json: stop at b"), std::string::npos);
}

TEST_F(TableReaderTest, FilterSkipsRejectedRecordsButChecksTheirStructure) {
  const std::string path = dir_.file("f.json");
  write_text(
      path,
      R"([{"token": "a", "sample": "keep", "x": [1]}, {"token": "b", "sample": "drop", "x": [2]},
{"sample": "keep", "token": "c", "x": [3]}])");
  std::vector<std::string> seen;
  const RecordFilter filter{{{1, [](const std::string& v) { return v == "keep"; }}}};
  Status s = stream_table(
      path, {"token", "sample", "x"},
      [&](const TableRecord& r, std::size_t index) {
        seen.push_back(r.fields[0].str + std::to_string(index) +
                       std::to_string(r.fields[2].nums.at(0)));
        return Status::ok();
      },
      filter);
  ASSERT_TRUE(s.is_ok()) << s.message();
  EXPECT_EQ(seen, (std::vector<std::string>{"a01.000000", "c23.000000"}));
  // Broken nesting inside a rejected record is still an error (its scalars are not parsed).
  write_text(path, R"([{"token": "b", "sample": "drop", "x": [2}])");
  s = stream_table(
      path, {"token", "sample", "x"}, [](const TableRecord&, std::size_t) { return Status::ok(); },
      filter);
  EXPECT_NE(s.message().find("malformed JSON at offset 41"), std::string::npos) << s.message();
  write_text(path, R"([{"token": "b", "sample": "drop", "x": ["unterminated]}])");
  s = stream_table(
      path, {"token", "sample", "x"}, [](const TableRecord&, std::size_t) { return Status::ok(); },
      filter);
  EXPECT_NE(s.message().find("malformed JSON at offset 40: missing a closing quotation mark"),
            std::string::npos)
      << s.message();
}

// Rejected records longer than one 64-byte block go through the block skipper: brackets inside
// strings, strings and arrays across block boundaries, escapes, and errors deep inside a record
// must behave exactly as in the byte-level path.
TEST_F(TableReaderTest, BlockSkipperAgreesWithTheByteLevelPathOnLongRecords) {
  const std::string path = dir_.file("long.json");
  std::string json = "[";
  std::vector<std::string> expected;
  for (int i = 0; i < 300; ++i) {
    const bool keep = i % 7 == 3;
    if (i) json += ",\n";
    json += "{\"token\": \"t" + std::to_string(i) + "\", \"sample\": \"" +
            (keep ? "keep" : "drop") + "\"";
    json += ", \"filename\": \"" + std::string(static_cast<std::size_t>(i % 97), 'x') + "{[}]] \"";
    json += ", \"nested\": [[" + std::to_string(i) + ", 2.5, [3]], {\"a\": \"}}}\", \"b\": [4]}]";
    if (i % 50 == 10) json += ", \"escaped\": \"quote \\\" and backslash \\\\ }\"";
    json += ", \"pad\": \"" + std::string(static_cast<std::size_t>((i * 13) % 131), ' ') + "\"}";
    if (keep) expected.push_back("t" + std::to_string(i) + ":" + std::to_string(i));
  }
  json += "]";
  write_text(path, json);
  const RecordFilter filter{{{1, [](const std::string& v) { return v == "keep"; }}}};
  std::vector<std::string> seen;
  Status s = stream_table(
      path, {"token", "sample", "nested"},
      [&](const TableRecord& r, std::size_t) {
        seen.push_back(r.fields[0].str + ":" +
                       std::to_string(static_cast<int>(r.fields[2].nums.front())));
        return Status::ok();
      },
      filter);
  ASSERT_TRUE(s.is_ok()) << s.message();
  EXPECT_EQ(seen, expected);

  // Errors far inside a long rejected record, each reported at the offending byte.
  const std::string head =
      R"([{"token": "b", "sample": "drop", "pad": ")" + std::string(150, 'p') + "\", ";
  struct Case {
    std::string body, needle, message;
  };
  const std::vector<Case> cases = {
      {R"("x": [1, 2}, "y": "z"}])", "}, \"y", "missing ',' or ']' after an array element"},
      {"\"x\": \"bad\x01zz\"}]", "\x01", "invalid control character in a string"},
      {R"("x": "never closed})", "\"never", "missing a closing quotation mark"},
  };
  for (const auto& c : cases) {
    const std::string doc = head + c.body + std::string(200, ' ');
    write_text(path, doc);
    s = stream_table(
        path, {"token", "sample"}, [](const TableRecord&, std::size_t) { return Status::ok(); },
        filter);
    const std::size_t offset = doc.find(c.needle);
    EXPECT_NE(
        s.message().find("malformed JSON at offset " + std::to_string(offset) + ": " + c.message),
        std::string::npos)
        << s.message();
  }
}

// The typed reads dataset and bag convert use: a field of another type, or a fractional number
// where an integer is expected, is refused (the caller reports the record), never converted.
TEST_F(TableReaderTest, TypedReadsRefuseOtherTypes) {
  const std::string json =
      R"([{"s": "x", "i": 1533151603547590, "f": 1.5, "e": 1e3, "b": true, "n": null, "l": [[1, 2], [3]],)"
      R"( "ls": ["a"], "o": {"k": 1}, "big": 99999999999999999999}])";
  ASSERT_TRUE(scan(json, {"s", "i", "f", "e", "b", "n", "l", "ls", "o", "big", "missing"}).is_ok());
  ASSERT_EQ(records_.size(), 1u);
  const auto& f = records_[0].fields;
  std::string s;
  std::int64_t i = 0;
  bool b = false;
  std::vector<double> v;
  EXPECT_TRUE(f[0].get(&s));
  EXPECT_EQ(s, "x");
  EXPECT_FALSE(f[0].get(&i));
  EXPECT_TRUE(f[1].get(&i));
  EXPECT_EQ(i, 1533151603547590);
  EXPECT_FALSE(f[1].get(&s));
  EXPECT_FALSE(f[2].get(&i));  // 1.5
  EXPECT_FALSE(f[3].get(&i));  // 1e3 is written as a float
  EXPECT_TRUE(f[4].get(&b));
  EXPECT_TRUE(b);
  EXPECT_EQ(f[5].kind, FieldKind::kNull);
  EXPECT_FALSE(f[5].get(&b));
  EXPECT_TRUE(f[6].get_numbers(&v));
  EXPECT_EQ(v, (std::vector<double>{1, 2, 3}));
  EXPECT_FALSE(f[7].get_numbers(&v));  // strings
  EXPECT_EQ(f[8].kind, FieldKind::kObject);
  EXPECT_EQ(f[9].kind, FieldKind::kNumber);
  EXPECT_FALSE(f[9].get(&i));  // beyond int64
  EXPECT_EQ(f[10].kind, FieldKind::kMissing);
  EXPECT_FALSE(f[10].present);
}

// A table cut short is kTruncated (the download or copy stopped), anything else malformed is
// kCorruptData; both name the file and the byte offset.
TEST_F(TableReaderTest, ATableCutShortIsTruncated) {
  const std::string whole = R"([{"token": "a", "timestamp": 1533151603547590, "flag": true}])";
  for (std::size_t cut : {std::size_t{1}, whole.find("\"a\"") + 1, whole.find("1533") + 4,
                          whole.find("true") + 2, whole.size() - 1}) {
    const Status s = scan(whole.substr(0, cut), {"token", "timestamp", "flag"});
    EXPECT_EQ(s.code(), StatusCode::kTruncated) << cut << ": " << s.message();
    EXPECT_NE(s.message().find("table.json: malformed JSON at offset"), std::string::npos)
        << s.message();
  }
  const Status bad = scan(R"([{"token": "a"} x])", {"token"});
  EXPECT_EQ(bad.code(), StatusCode::kCorruptData) << bad.message();
}

TEST_F(TableReaderTest, BadEscapesAreReportedAtTheirByte) {
  struct Case {
    std::string json, message;
    std::size_t offset;
  };
  const std::vector<Case> cases = {
      {R"([{"token": "ab\q"}])", "invalid escape in a string", 15},
      {R"([{"token": "ab\u12G4"}])", "invalid \\u escape in a string", 15},
      {R"([{"token": "ab\ud83dx"}])", "invalid surrogate pair in a string", 19},
  };
  for (const auto& c : cases) {
    const Status s = scan(c.json, {"token"});
    EXPECT_EQ(s.code(), StatusCode::kCorruptData);
    EXPECT_NE(
        s.message().find("malformed JSON at offset " + std::to_string(c.offset) + ": " + c.message),
        std::string::npos)
        << c.json << " -> " << s.message();
  }
}

}  // namespace
}  // namespace faultline::nuscenes
