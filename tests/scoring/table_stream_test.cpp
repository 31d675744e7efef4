// The table scanner: decoded fields, skipped fields, Python's JSON extensions, errors with byte
// offsets.
#include "scoring/table_stream.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "test_util.hpp"

namespace faultline::scoring {
namespace {

using testing::TempDir;
using testing::write_text;

class TableStreamTest : public ::testing::Test {
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
  TempDir dir_{"table_stream"};
  std::vector<TableRecord> records_;
};

TEST_F(TableStreamTest, DecodesWantedFieldsAndSkipsTheRest) {
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

TEST_F(TableStreamTest, FlattensNestedListsAndKeepsStringLists) {
  const std::string json =
      R"([{"camera_intrinsic": [[1, 0, 2], [0, 3, 4], [0, 0, 1]], "attribute_tokens": ["x", "y"]}])";
  ASSERT_TRUE(scan(json, {"camera_intrinsic", "attribute_tokens"}).is_ok());
  ASSERT_EQ(records_.size(), 1u);
  EXPECT_EQ(records_[0].fields[0].nums, (std::vector<double>{1, 0, 2, 0, 3, 4, 0, 0, 1}));
  EXPECT_EQ(records_[0].fields[1].strs, (std::vector<std::string>{"x", "y"}));
}

TEST_F(TableStreamTest, ReadsPythonNanInfinityAndUnicodeEscapes) {
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

TEST_F(TableStreamTest, ParsesNumbersExactly) {
  const std::string json =
      R"([{"t": 1533151603547590, "x": 0.1, "y": 2.220446049250313e-16, "z": -0}])";
  ASSERT_TRUE(scan(json, {"t", "x", "y", "z"}).is_ok());
  EXPECT_EQ(records_[0].fields[0].num, 1533151603547590.0);
  EXPECT_EQ(records_[0].fields[1].num, 0.1);
  EXPECT_EQ(records_[0].fields[2].num, 2.220446049250313e-16);
  EXPECT_TRUE(std::signbit(records_[0].fields[3].num));
}

TEST_F(TableStreamTest, EmptyArrayHasNoRecords) {
  ASSERT_TRUE(scan(" [ ] \n", {"token"}).is_ok());
  EXPECT_TRUE(records_.empty());
}

TEST_F(TableStreamTest, ErrorsNameTheFileAndTheByteOffset) {
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

TEST_F(TableStreamTest, RejectsAnObjectRootAndAMissingFile) {
  const Status s = scan(R"({"token": "a"})", {"token"});
  EXPECT_NE(s.message().find("must be a JSON array"), std::string::npos) << s.message();
  const Status missing = stream_table(dir_.file("nope.json"), {"token"},
                                      [](const TableRecord&, std::size_t) { return Status::ok(); });
  EXPECT_EQ(missing.code(), StatusCode::kNotFound);
  EXPECT_NE(missing.message().find("nope.json: table not found"), std::string::npos);
}

TEST_F(TableStreamTest, CallbackErrorStopsTheScan) {
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

TEST_F(TableStreamTest, FilterSkipsRejectedRecordsButChecksTheirStructure) {
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

// Rejected records longer than one 64-byte block go through the block skipper: brackets inside strings, strings
// and arrays across block boundaries, escapes, and errors deep inside a record must behave exactly as in the
// byte-level path.
TEST_F(TableStreamTest, BlockSkipperAgreesWithTheByteLevelPathOnLongRecords) {
  const std::string path = dir_.file("long.json");
  std::string json = "[";
  std::vector<std::string> expected;
  for (int i = 0; i < 300; ++i) {
    const bool keep = i % 7 == 3;
    if (i) json += ",\n";
    json += "{\"token\": \"t" + std::to_string(i) + "\", \"sample\": \"" + (keep ? "keep" : "drop") + "\"";
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
        seen.push_back(r.fields[0].str + ":" + std::to_string(static_cast<int>(r.fields[2].nums.front())));
        return Status::ok();
      },
      filter);
  ASSERT_TRUE(s.is_ok()) << s.message();
  EXPECT_EQ(seen, expected);

  // Errors far inside a long rejected record, each reported at the offending byte.
  const std::string head = R"([{"token": "b", "sample": "drop", "pad": ")" + std::string(150, 'p') + "\", ";
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
        path, {"token", "sample"}, [](const TableRecord&, std::size_t) { return Status::ok(); }, filter);
    const std::size_t offset = doc.find(c.needle);
    EXPECT_NE(s.message().find("malformed JSON at offset " + std::to_string(offset) + ": " + c.message),
              std::string::npos)
        << s.message();
  }
}

}  // namespace
}  // namespace faultline::scoring
