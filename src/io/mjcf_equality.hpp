// MJCF equality constraints as loops (mjcf_equality.cpp): MuJoCo's compiled <equality connect>
// and <equality weld> on the model bodies their MuJoCo bodies move with.  Internal: built only
// with MuJoCo.
#pragma once

#include "soadyn/algorithm/loops.hpp"

#include <mujoco/mujoco.h>

#include <functional>
#include <string>
#include <vector>

namespace soadyn::mjcf_detail {

// X given in MuJoCo body b's frame (0: the world) as a placement on a model body (body; −1: the world)
using PlaceOnModel = std::function<Placement(int b, const Placement& X, int& body)>;

struct EqualityLoops {
  std::vector<LoopConstraint> loops;  // the active connects and welds, in MuJoCo's order
  std::vector<std::string> ignored;   // the "ignored: …" line's parts: the equalities not held, and
                                      // the softness of those held
};

// The loops of m's equalities (mjcf.hpp, MjcfModel::loops): connect → point, weld → weld (a point
// with torquescale 0); inactive, joint and tendon equalities, and one within a rigid body, are
// named in `ignored`
EqualityLoops equality_loops(const mjModel* m, const PlaceOnModel& place);

}  // namespace soadyn::mjcf_detail
