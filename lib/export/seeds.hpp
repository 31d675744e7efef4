// Per-output seed derivation: a pure function of (run seed, condition, level, key), so outputs do
// not depend on thread count, shard or file order (docs/export.md "Seeds").
//   h    = FNV-1a-64 of "<ClassName>/<level>/<key>"
//   s64  = splitmix64(run_seed XOR splitmix64(h))
//   numpy mode: np.random.seed(uint32(s64 >> 32)) immediately before the one corruption call
//   fast mode:  FastRng(s64)
// Keys: image corruptions use the output path relative to the level folder
// ("CAM_FRONT/<file>.jpg"); FrameLost uses the sample token (6 uniforms in camera order per
// sample); CameraCrash uses "run" (one dead set per run, as the reference draws it once per
// severity pass).
#pragma once

#include <cstdint>
#include <string>

#include "corruption/types.hpp"
#include "export/conditions.hpp"

namespace faultline::exporter {

std::uint64_t splitmix64(std::uint64_t x);

std::uint64_t derive_seed64(std::uint64_t run_seed, Condition c, corruption::Level level,
                            const std::string& key);
std::uint32_t numpy_seed(std::uint64_t seed64);  // upper 32 bits: np.random.seed takes a uint32

}  // namespace faultline::exporter
