// Scenario files (YAML) and URDF import.
//
// A scenario states only what its scene has: bodies (or a URDF), gravity, an initial state,
// and, when the scene needs them, simulation settings and inputs.  Everything else has a
// documented default (scenarios/README.md).  Every mistake is reported as
// `file:line:column: field: message` through soadyn::Error.
#pragma once

#include "soadyn/io/input_file.hpp"
#include "soadyn/sim/scenario.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace soadyn {

// Loads a .yaml scenario or a .urdf (then: zero initial state, default settings, no inputs).
// `gravity` overrides the file's gravity; a URDF's default is urdf_gravity().  `inertia_check`
// overrides a scenario's `inertia_check:` (default InertiaCheck::Warn, see model.hpp).
Scenario load_scenario(const std::string& path, bool free_root = false,
                       const std::optional<Vec3>& gravity = std::nullopt,
                       std::optional<InertiaCheck> inertia_check = std::nullopt);

// Parses scenario text; `path` names it in messages and anchors a relative `urdf:`.  `robot_text`:
// the robot file's text as a run stored it (soadyn view), read instead of the file urdf: names.
// `model_files`: an MJCF robot's files as a run stored them (Scenario::model_files), compiled from
// those alone (parse_mjcf_files), never from the disk.
Scenario parse_scenario(const std::string& text, const std::string& path, bool free_root = false,
                        std::optional<InertiaCheck> inertia_check = std::nullopt,
                        const std::optional<std::string>& robot_text = std::nullopt,
                        const std::vector<ModelFile>* model_files = nullptr);

// "warn", "balance", "strict" (the scenario's and the command line's words); nullopt otherwise.
std::optional<InertiaCheck> parse_inertia_check(const std::string& s);

// The gravity of a URDF robot wherever it enters (a .urdf given to load_scenario, `urdf:` in a
// scenario), unless the scenario's `gravity:` or the caller says otherwise: m/s², z up.
inline Vec3 urdf_gravity() { return Vec3(0, 0, -9.81); }

// URDF import.  Fixed joints are merged; the root link is welded to the world unless the URDF
// has a floating joint or free_root is set.
Model load_urdf(const std::string& path, bool free_root, const Vec3& gravity,
                InertiaCheck inertia_check = InertiaCheck::Warn);
Model parse_urdf(const std::string& xml, const std::string& path, bool free_root, const Vec3& gravity,
                 InertiaCheck inertia_check = InertiaCheck::Warn);

// The largest magnitude of an initial coordinate or speed (m, rad, m/s, rad/s) a scenario or the
// command line may give: past it a double resolves no finer than 1e-10 of the value, coarser than
// the integrators' tolerances, and a run would stall rather than fail (1e300 rad did).
inline constexpr double kMaxStateMagnitude = 1e6;

// The largest model or scenario file read (input_file.hpp's kMaxModelBytes, 64 MiB): real robot
// descriptions are well under a megabyte; the cap keeps a wrong file from exhausting memory.
inline constexpr std::uint64_t kMaxInputBytes = kMaxModelBytes;

// A model or scenario file's text: a regular file (a FIFO, device or directory is refused with its
// kind, never waited on: input_file.hpp), at most kMaxInputBytes, not empty, no NUL bytes.  Throws
// soadyn::Error naming the file.
std::string read_text_file(const std::string& path);

}  // namespace soadyn
