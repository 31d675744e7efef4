// Python-compatible number printing, JSON layout and the bundled split lists.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "scoring/py_json.hpp"
#include "scoring/splits.hpp"

namespace faultline::scoring {
namespace {

TEST(PyFloatTest, PrintsLikePythonRepr) {
  EXPECT_EQ(py_float(0.35000000000000003), "0.35000000000000003");
  EXPECT_EQ(py_float(1.0), "1.0");
  EXPECT_EQ(py_float(0.0), "0.0");
  EXPECT_EQ(py_float(1e-05), "1e-05");
  EXPECT_EQ(py_float(0.0001), "0.0001");
  EXPECT_EQ(py_float(1e16), "1e+16");
  EXPECT_EQ(py_float(1234567890123456.0), "1234567890123456.0");
  EXPECT_EQ(py_float(-2.5e-07), "-2.5e-07");
  EXPECT_EQ(py_float(1.0000000000000004), "1.0000000000000004");
  EXPECT_EQ(py_float(std::nan("")), "NaN");
}

TEST(PyJsonWriterTest, IndentTwoLayout) {
  PyJsonWriter w;
  w.begin_object();
  w.key("a");
  w.begin_array();
  w.value(0.5);
  w.value_int(2);
  w.end_array();
  w.key("b");
  w.begin_object();
  w.end_object();
  w.key("c");
  w.value_string("x\"\xc3\xa9");
  w.end_object();
  EXPECT_EQ(w.str(),
            "{\n  \"a\": [\n    0.5,\n    2\n  ],\n  \"b\": {},\n  \"c\": \"x\\\"\\u00e9\"\n}");
}

TEST(SplitsTest, DevkitSceneCountsAndDisjointness) {
  auto train = predefined_split_scenes("train", "v1.0-trainval");
  auto val = predefined_split_scenes("val", "v1.0-trainval");
  auto test = predefined_split_scenes("test", "v1.0-test");
  ASSERT_TRUE(train.is_ok() && val.is_ok() && test.is_ok());
  EXPECT_EQ(train->size(), 700u);
  EXPECT_EQ(val->size(), 150u);
  EXPECT_EQ(test->size(), 150u);
  std::set<std::string> all(train->begin(), train->end());
  all.insert(val->begin(), val->end());
  all.insert(test->begin(), test->end());
  EXPECT_EQ(all.size(), 1000u);  // the devkit's own assertion
  auto mini_val = predefined_split_scenes("mini_val", "v1.0-mini");
  ASSERT_TRUE(mini_val.is_ok());
  EXPECT_EQ(*mini_val, (std::vector<std::string>{"scene-0103", "scene-0916"}));
  EXPECT_EQ(predefined_split_scenes("mini_train", "v1.0-mini")->size(), 8u);
}

TEST(SplitsTest, VersionMismatchAndUnbundledSplitsAreErrors) {
  auto r = predefined_split_scenes("val", "v1.0-mini");
  ASSERT_FALSE(r.is_ok());
  EXPECT_NE(r.status().message().find("not compatible"), std::string::npos);
  EXPECT_FALSE(predefined_split_scenes("mini_val", "v1.0-trainval").is_ok());
  auto td = predefined_split_scenes("train_detect", "v1.0-trainval");
  ASSERT_FALSE(td.is_ok());
  EXPECT_EQ(td.status().code(), StatusCode::kUnsupported);
  EXPECT_TRUE(is_predefined_split("train_track"));
  EXPECT_FALSE(is_predefined_split("custom_0916_0553"));
}

}  // namespace
}  // namespace faultline::scoring
