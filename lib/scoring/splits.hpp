// Predefined nuScenes splits (scene names from the devkit's utils/splits.py) and custom splits.json
// lookup.
#pragma once

#include <string>
#include <vector>

#include "common/status.hpp"

namespace faultline::scoring {

// True for train, val, test, mini_train, mini_val, train_detect, train_track.
bool is_predefined_split(const std::string& split);

// Checks that a predefined split fits the version (devkit: train/val/train_* need *trainval, mini_*
// need *mini, test needs *test) and returns its scene names. train_detect/train_track are not
// bundled (their lists could not be obtained from a trustworthy copy of the devkit); they give
// kUnsupported.
Result<std::vector<std::string>> predefined_split_scenes(const std::string& split,
                                                         const std::string& version);

// Reads <dataroot>/<version>/splits.json and returns the named list of scene names.
Result<std::vector<std::string>> custom_split_scenes(const std::string& split,
                                                     const std::string& dataroot,
                                                     const std::string& version);

}  // namespace faultline::scoring
