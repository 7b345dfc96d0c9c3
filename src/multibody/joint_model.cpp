#include "soadyn/multibody/joint_model.hpp"

namespace soadyn {

namespace {

// k + 1 with the sign when the axis is exactly ±e_k, else 0
int unit_axis_of(const Vec3& axis) {
  for (int k = 0; k < 3; ++k) {
    if (axis == Vec3::Unit(k)) return k + 1;
    if (axis == -Vec3::Unit(k)) return -(k + 1);
  }
  return 0;
}

// Kind<k> along sign · e_k, for unit = ±(k + 1); `turned` for the prismatic kinds
template <template <int> class Kind>
JointModel along(int unit, bool turned = false) {
  const auto make = [&](auto kind) -> JointModel {
    kind.sign = unit > 0 ? 1.0 : -1.0;
    if constexpr (requires { kind.turned; }) kind.turned = turned;
    return kind;
  };
  switch (std::abs(unit)) {
    case 1: return make(Kind<0>{});
    case 2: return make(Kind<1>{});
    case 3: return make(Kind<2>{});
  }
  throw Error("classify_joint: unit axis " + std::to_string(unit) + " out of range");
}

}  // namespace

JointModel classify_joint(JointType type, const Vec3& axis, const Mat3& placement_rotation, double pitch) {
  const bool turned = placement_rotation != Mat3::Identity();
  switch (type) {
    case JointType::Revolute:
      if (const int unit = unit_axis_of(axis))
        return turned ? along<joints::TurnedRevoluteAxis>(unit) : along<joints::RevoluteAxis>(unit);
      return joints::Revolute{{}, axis};
    case JointType::Prismatic:
      if (const int unit = unit_axis_of(axis)) return along<joints::PrismaticAxis>(unit, turned);
      return joints::Prismatic{{}, axis};
    case JointType::Ball: return joints::Ball{};
    case JointType::Planar: {
      joints::Planar j{{}, axis, {}, {}};
      plane_basis(axis, j.e1, j.e2);
      return j;
    }
    case JointType::Free: return joints::Free{};
    case JointType::Helical: return joints::Helical{{}, axis, pitch};
    case JointType::Fixed: throw Error("classify_joint: a fixed joint has no kind (Model::build merges it away)");
  }
  throw Error("classify_joint: unknown joint type " + std::to_string(static_cast<int>(type)));
}

namespace {
template <class... F>
struct Overload : F... {
  using F::operator()...;
};
template <class... F>
Overload(F...) -> Overload<F...>;
}  // namespace

bool turns_by_angle(const JointModel& joint) {
  return std::visit(Overload{[](const joints::RevoluteAxis<0>&) { return true; },
                             [](const joints::RevoluteAxis<1>&) { return true; },
                             [](const joints::RevoluteAxis<2>&) { return true; },
                             [](const joints::TurnedRevoluteAxis<0>&) { return true; },
                             [](const joints::TurnedRevoluteAxis<1>&) { return true; },
                             [](const joints::TurnedRevoluteAxis<2>&) { return true; },
                             [](const auto&) { return false; }},
                    joint);
}

const char* kind_name(const JointModel& joint) {
  static const char* const names[] = {
      "revolute-axis-x", "revolute-axis-y", "revolute-axis-z", "turned-revolute-axis-x", "turned-revolute-axis-y",
      "turned-revolute-axis-z", "prismatic-axis-x", "prismatic-axis-y", "prismatic-axis-z", "revolute",
      "prismatic", "ball", "planar", "free", "helical"};
  static_assert(std::size(names) == std::variant_size_v<JointModel>);
  return names[joint.index()];
}

}  // namespace soadyn
