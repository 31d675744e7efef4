// The table writer: the devkit's json.dump(indent=0) layout byte for byte, the compact layout, and
// both read back by the one reader with every value intact.
#include "nuscenes/table_writer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "nuscenes/table_reader.hpp"
#include "test_util.hpp"

namespace faultline::nuscenes {
namespace {

using testing::read_text;
using testing::TempDir;

class TableWriterTest : public ::testing::Test {
 protected:
  // Two records covering every field type, in `layout`; returns the file's text.
  std::string Write(TableLayout layout) {
    TableWriter w(layout);
    EXPECT_TRUE(w.open(path_).is_ok());
    w.begin_record();
    w.field("token", "a\"b\\c");
    w.field("timestamp", std::int64_t{1533151603547590});
    w.field("x", 0.1);
    w.field("fixed", 1.0 / 3.0, 4);
    w.field("flag", true);
    w.field("translation", std::vector<double>{1.5, -2.0, 0.0});
    w.field("tokens", std::vector<std::string>{"p", "q"});
    w.matrix("camera_intrinsic", {{1, 0}, {0, 1}});
    w.end_record();
    w.begin_record();
    w.field("token", "d");
    w.field("translation", std::vector<double>{});
    w.matrix("camera_intrinsic", {});
    w.end_record();
    EXPECT_TRUE(w.close().is_ok());
    EXPECT_EQ(w.records(), 2);
    const std::string text = read_text(path_);
    EXPECT_EQ(w.bytes(), static_cast<std::int64_t>(text.size()));
    return text;
  }

  void ExpectReadBack() {
    std::vector<TableRecord> records;
    const Status s = stream_table(
        path_,
        {"token", "timestamp", "x", "fixed", "flag", "translation", "tokens", "camera_intrinsic"},
        [&](const TableRecord& r, std::size_t) {
          records.push_back(r);
          return Status::ok();
        });
    ASSERT_TRUE(s.is_ok()) << s.message();
    ASSERT_EQ(records.size(), 2u);
    const auto& f = records[0].fields;
    EXPECT_EQ(f[0].str, "a\"b\\c");
    EXPECT_EQ(f[1].integer, 1533151603547590);
    EXPECT_EQ(f[2].num, 0.1);
    EXPECT_EQ(f[3].num, 0.3333);
    EXPECT_TRUE(f[4].boolean);
    EXPECT_EQ(f[5].nums, (std::vector<double>{1.5, -2.0, 0.0}));
    EXPECT_EQ(f[6].strs, (std::vector<std::string>{"p", "q"}));
    EXPECT_EQ(f[7].nums, (std::vector<double>{1, 0, 0, 1}));
    EXPECT_EQ(records[1].fields[5].kind, FieldKind::kList);
    EXPECT_TRUE(records[1].fields[5].nums.empty());
  }

  TempDir dir_{"table_writer"};
  std::string path_ = dir_.file("table.json");
};

TEST_F(TableWriterTest, Indent0LayoutIsTheDevkits) {
  const std::string text = Write(TableLayout::kIndent0);
  EXPECT_EQ(text,
            "[\n{\n\"token\": \"a\\\"b\\\\c\",\n\"timestamp\": 1533151603547590,\n\"x\": "
            "0.1,\n\"fixed\": 0.3333,\n"
            "\"flag\": true,\n\"translation\": [\n1.5,\n-2.0,\n0.0\n],\n\"tokens\": "
            "[\n\"p\",\n\"q\"\n],\n"
            "\"camera_intrinsic\": [\n[\n1.0,\n0.0\n],\n[\n0.0,\n1.0\n]\n]\n},\n"
            "{\n\"token\": \"d\",\n\"translation\": [],\n\"camera_intrinsic\": []\n}\n]");
  ExpectReadBack();
}

TEST_F(TableWriterTest, CompactLayoutHasOneRecordPerLine) {
  const std::string text = Write(TableLayout::kCompact);
  EXPECT_EQ(text,
            "[\n{\"token\": \"a\\\"b\\\\c\", \"timestamp\": 1533151603547590, \"x\": 0.1, "
            "\"fixed\": 0.3333, "
            "\"flag\": true, \"translation\": [1.5, -2.0, 0.0], \"tokens\": [\"p\", \"q\"], "
            "\"camera_intrinsic\": [[1.0, 0.0], [0.0, 1.0]]},\n"
            "{\"token\": \"d\", \"translation\": [], \"camera_intrinsic\": []}\n]\n");
  ExpectReadBack();
}

TEST(FormatDoubleTest, WritesPythonsReprForms) {
  EXPECT_EQ(format_double(0.0), "0.0");
  EXPECT_EQ(format_double(1.5), "1.5");
  EXPECT_EQ(format_double(1e-05), "1e-05");
  EXPECT_EQ(format_double(std::numeric_limits<double>::quiet_NaN()), "NaN");
  EXPECT_EQ(format_double(-std::numeric_limits<double>::infinity()), "-Infinity");
}

TEST(TableWriterOpenTest, AnUnwritablePathIsNamed) {
  TableWriter w;
  const Status s = w.open("/nonexistent-dir/table.json");
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find("/nonexistent-dir/table.json"), std::string::npos);
}

}  // namespace
}  // namespace faultline::nuscenes
