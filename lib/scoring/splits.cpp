// Scene lists of the devkit's python-sdk/nuscenes/utils/splits.py, stored as inclusive ranges of
// scene numbers (the devkit lists are sorted, so ranges are lossless). A unit test checks the
// counts (700 / 150 / 150) and that train + val + test are 1000 distinct scenes, as the devkit
// asserts.
#include "scoring/splits.hpp"

#include <rapidjson/document.h>
#include <rapidjson/error/en.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <utility>

#include "common/bounded_read.hpp"

namespace faultline::scoring {
namespace {

using Ranges = std::vector<std::pair<int, int>>;

const Ranges kTrain = {
    {1, 2},       {4, 11},     {19, 34},   {41, 76},   {120, 135}, {138, 139},  {149, 152},
    {154, 155},   {157, 168},  {170, 185}, {187, 188}, {190, 196}, {199, 200},  {202, 204},
    {206, 214},   {218, 220},  {222, 222}, {224, 264}, {283, 306}, {315, 318},  {321, 321},
    {323, 324},   {328, 328},  {347, 386}, {388, 403}, {405, 408}, {410, 459},  {461, 465},
    {467, 469},   {471, 472},  {474, 480}, {499, 502}, {504, 515}, {517, 518},  {525, 539},
    {541, 546},   {566, 566},  {568, 568}, {570, 578}, {580, 580}, {582, 600},  {639, 679},
    {681, 681},   {683, 689},  {695, 698}, {700, 701}, {703, 719}, {726, 728},  {730, 731},
    {733, 741},   {744, 744},  {746, 747}, {749, 752}, {757, 765}, {767, 769},  {786, 787},
    {789, 792},   {803, 806},  {808, 813}, {815, 817}, {819, 822}, {847, 856},  {858, 858},
    {860, 866},   {868, 873},  {875, 878}, {880, 880}, {882, 903}, {945, 945},  {947, 947},
    {949, 949},   {952, 953},  {955, 961}, {975, 984}, {988, 992}, {994, 1025}, {1044, 1058},
    {1074, 1102}, {1104, 1110}};

const Ranges kVal = {{3, 3},     {12, 18},    {35, 36},   {38, 39},   {92, 110},  {221, 221},
                     {268, 278}, {329, 332},  {344, 346}, {519, 524}, {552, 565}, {625, 627},
                     {629, 630}, {632, 638},  {770, 771}, {775, 775}, {777, 778}, {780, 784},
                     {794, 800}, {802, 802},  {904, 917}, {919, 931}, {962, 963}, {966, 969},
                     {971, 972}, {1059, 1073}};

const Ranges kTest = {{77, 91},   {111, 119}, {140, 140}, {142, 148}, {265, 266}, {279, 282},
                      {307, 314}, {333, 343}, {481, 498}, {547, 551}, {601, 604}, {606, 624},
                      {827, 831}, {833, 842}, {844, 846}, {932, 933}, {935, 943}, {1026, 1043}};

const Ranges kMiniTrain = {{61, 61},   {553, 553},   {655, 655},   {757, 757},
                           {796, 796}, {1077, 1077}, {1094, 1094}, {1100, 1100}};
const Ranges kMiniVal = {{103, 103}, {916, 916}};

std::vector<std::string> expand(const Ranges& ranges) {
  std::vector<std::string> names;
  for (const auto& [lo, hi] : ranges) {
    for (int n = lo; n <= hi; ++n) {
      char buf[16];
      std::snprintf(buf, sizeof buf, "scene-%04d", n);
      names.emplace_back(buf);
    }
  }
  return names;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

bool is_predefined_split(const std::string& split) {
  return split == "train" || split == "val" || split == "test" || split == "mini_train" ||
         split == "mini_val" || split == "train_detect" || split == "train_track";
}

Result<std::vector<std::string>> predefined_split_scenes(const std::string& split,
                                                         const std::string& version) {
  std::string needed;
  if (split == "train" || split == "val" || split == "train_detect" || split == "train_track") {
    needed = "trainval";
  } else if (split == "mini_train" || split == "mini_val") {
    needed = "mini";
  } else if (split == "test") {
    needed = "test";
  } else {
    return Status(StatusCode::kInvalidArgument, "'" + split + "' is not a predefined split");
  }
  if (!ends_with(version, needed)) {
    return Status(StatusCode::kInvalidArgument,
                  "Requested split " + split + " which is not compatible with NuScenes version " +
                      version + " (needs a version ending in '" + needed + "')");
  }
  if (split == "train") return expand(kTrain);
  if (split == "val") return expand(kVal);
  if (split == "test") return expand(kTest);
  if (split == "mini_train") return expand(kMiniTrain);
  if (split == "mini_val") return expand(kMiniVal);
  return Status(
      StatusCode::kUnsupported,
      "split " + split +
          ": its scene list is not bundled with Faultline; define it in "
          "<dataroot>/<version>/splits.json under another name and use that custom split");
}

Result<std::vector<std::string>> custom_split_scenes(const std::string& split,
                                                     const std::string& dataroot,
                                                     const std::string& version) {
  const std::string path = dataroot + "/" + version + "/splits.json";
  auto read =
      read_file_bounded(path, kMaxParamsFileBytes, "custom split '" + split + "': splits file");
  if (!read.is_ok()) return read.status();
  const std::string text = std::move(read).value();
  rapidjson::Document doc;
  doc.Parse(text.c_str(), text.size());
  if (doc.HasParseError()) {
    return Status(StatusCode::kCorruptData, path + ": invalid JSON at offset " +
                                                std::to_string(doc.GetErrorOffset()) + ": " +
                                                rapidjson::GetParseError_En(doc.GetParseError()));
  }
  if (!doc.IsObject())
    return Status(StatusCode::kCorruptData, path + ": top level must be an object");
  auto it = doc.FindMember(split.c_str());
  if (it == doc.MemberEnd()) {
    return Status(StatusCode::kNotFound, "custom split '" + split + "' is not defined in " + path);
  }
  if (!it->value.IsArray()) {
    return Status(StatusCode::kCorruptData,
                  path + ": split '" + split + "' must be a list of scene names");
  }
  std::vector<std::string> names;
  for (const auto& v : it->value.GetArray()) {
    if (!v.IsString()) {
      return Status(StatusCode::kCorruptData,
                    path + ": split '" + split + "' holds a non-string entry");
    }
    names.emplace_back(v.GetString(), v.GetStringLength());
  }
  return names;
}

}  // namespace faultline::scoring
