// What each corruption is, for people: where its definition comes from, how closely numpy mode
// follows that reference (docs/faults.md "Fidelity"), and its parameters at a severity, read from
// the same parameter functions the kernels use (so the catalogue cannot drift from them).
#pragma once

#include <string>

#include "corruption/types.hpp"

namespace faultline::corruption {

// How numpy mode (--rng numpy) relates to the reference.
enum class Fidelity {
  ReferenceExact,  // the reference's output array bit for bit after np.random.seed(seed)
  Statistical,     // the reference cannot be reproduced draw for draw; its statistics are matched
  Own,             // Faultline's definition: no reference has it
};

const char* to_string(Fidelity f);  // "reference-exact" | "statistical" | "own"

// The class of the corruption as a whole. iso_noise and dark are reference-exact at severities 1..4
// and Faultline's own at 5 (the reference raises IndexError there): see fidelity_note.
Fidelity fidelity(Corruption c);

// Where the definition comes from: "nuScenes-C", "imagecorruptions 1.1.2", "RoboBEV" or
// "Faultline".
const char* origin(Corruption c);

// A caveat to the class ("severity 5 own: ..."), or "" when there is none.
const char* fidelity_note(Corruption c);

// The corruption's parameters at `severity` (1..5; clamped), short and with units, e.g.
// "σ 0.08" or "quality 30, 1 generation". rolling_shutter's depend on the yaw rate as well, so
// its text gives the readout time only.
std::string severity_parameters(Corruption c, int severity);

}  // namespace faultline::corruption
