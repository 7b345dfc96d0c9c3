// Frames: placement, velocity, acceleration and Jacobians (frames.hpp), each one walk up the
// ancestors of the frame's body through the telescoped D_{b:j} of Ψ_D.
#include "soadyn/algorithm/frames.hpp"

#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/operators.hpp"
#include "soadyn/multibody/text.hpp"

#include "point_motion.hpp"

namespace soadyn {

const std::vector<ReferenceInfo>& references() {
  static const std::vector<ReferenceInfo> table{
      {Reference::World, "world", "[ω; v_O]: the body's point at the inertial origin, inertial axes (spatial)"},
      {Reference::Local, "local", "[ω; ṗ] in the frame's own axes, about its origin"},
      {Reference::LocalWorldAligned, "local_world_aligned", "[ω; ṗ] in inertial axes, about the frame's origin"},
  };
  return table;
}

std::string_view to_string(Reference r) {
  for (const ReferenceInfo& info : references())
    if (info.reference == r) return info.name;
  throw Error("to_string: unknown reference " + std::to_string(int(r)));
}

Reference parse_reference(std::string_view s) {
  std::vector<std::string> names;
  for (const ReferenceInfo& info : references()) {
    if (info.name == s) return info.reference;
    names.emplace_back(info.name);
  }
  throw Error("reference: unknown reference '" + printable(std::string(s)) + "'" + did_you_mean(std::string(s), names));
}

namespace {

void check_frame(const Model& model, const char* where, int frame) {
  if (frame < 0 || frame >= int(model.frame_names.size()))
    throw Error(std::string(where) + ": frame: expected an index 0.." + std::to_string(int(model.frame_names.size()) - 1) +
                ", got " + std::to_string(frame));
}

void check_body(const Model& model, const char* where, int body) {
  if (body < -1 || body >= model.nbodies)
    throw Error(std::string(where) + ": body: expected -1 (the world) .. " + std::to_string(model.nbodies - 1) + ", got " +
                std::to_string(body));
}

// the frame X on body b at the current [kin] state: R = C_b X.R, p = η_b + C_b X.p
Placement place_on(const Data& data, int b, const Placement& X) {
  if (b < 0) return X;
  return {data.R[b] * X.R, Vec3(data.eta.col(b)) + data.R[b] * X.p};
}

Placement place(const Model& model, const Data& data, int frame) {
  return place_on(data, model.frame_body[frame], model.frame_placement[frame]);
}

// ω and ṗ of the body's point p: ṗ = η̇_b + ω_b × (p − η_b)   (zero on the world)
void point_velocity(const Data& data, int b, const Vec3& p, Vec3& w, Vec3& pd) {
  if (b < 0) {
    w.setZero(), pd.setZero();
    return;
  }
  w = data.V.col(b).head<3>();
  pd = data.V.col(b).tail<3>() + w.cross(p - data.eta.col(b));
}

// [a; b] in the reference, from the same pair about p in inertial axes (a velocity's or a
// Jacobian column's: linear in the pair; world: b − a × p)
template <class A, class B>
void to_reference(Reference reference, const Placement& X, A&& a, B&& b) {
  switch (reference) {
    case Reference::LocalWorldAligned: return;
    case Reference::Local: {
      const Vec3 la = X.R.transpose() * a, lb = X.R.transpose() * b;
      a = la, b = lb;
      return;
    }
    case Reference::World: b -= Vec3(a).cross(X.p); return;
  }
  throw Error("frames: unknown reference " + std::to_string(int(reference)));
}

// the Jacobian columns of the body's point p in inertial axes about p, into J (6×nv, zeroed)
// then turned to the reference: column k of DOF k on body j is [g; u + g × (p − η_j)]
// (world: [g; u − g × η_j], local: both turned by Rᵀ); each column written as two 3-vectors
template <Reference kReference>
void point_columns_in(const Model& model, const Data& data, int b, const Placement& X, MatX& J) {
  if (J.rows() != 6 || J.cols() != model.nv) J.resize(6, model.nv);
  J.setZero();
  const Mat3 Rt = X.R.transpose();
  for (int j = b; j >= 0; j = model.parent[j]) {
    const Vec3 eta = data.eta.col(j);
    const Vec3 r = kReference == Reference::World ? Vec3(-eta) : Vec3(X.p - eta);
    for (int k = model.idx_v[j], end = k + model.nv_i[j]; k < end; ++k) {
      const Vec3 g = data.G.col(k).head<3>();
      const Vec3 c = data.G.col(k).tail<3>() + g.cross(r);
      Eigen::Map<Vec3> top(J.col(k).data()), bottom(J.col(k).data() + 3);
      if constexpr (kReference == Reference::Local) top.noalias() = Rt * g, bottom.noalias() = Rt * c;
      else top = g, bottom = c;
    }
  }
}

void point_columns(const Model& model, const Data& data, int b, const Placement& X, Reference reference, MatX& J) {
  switch (reference) {
    case Reference::LocalWorldAligned: return point_columns_in<Reference::LocalWorldAligned>(model, data, b, X, J);
    case Reference::Local: return point_columns_in<Reference::Local>(model, data, b, X, J);
    case Reference::World: return point_columns_in<Reference::World>(model, data, b, X, J);
  }
  throw Error("frames: unknown reference " + std::to_string(int(reference)));
}

}  // namespace

Placement frame_placement(const Model& model, const Data& data, int frame) {
  check_frame(model, "frame_placement", frame);
  return place(model, data, frame);
}

Vec6 frame_velocity(const Model& model, const Data& data, int frame, Reference reference) {
  check_frame(model, "frame_velocity", frame);
  return body_frame_velocity(model, data, model.frame_body[frame], model.frame_placement[frame], reference);
}

Placement body_frame_placement(const Model& model, const Data& data, int body, const Placement& X) {
  check_body(model, "body_frame_placement", body);
  return place_on(data, body, X);
}

Vec6 body_frame_velocity(const Model& model, const Data& data, int body, const Placement& on_body, Reference reference) {
  check_body(model, "body_frame_velocity", body);
  const Placement X = place_on(data, body, on_body);
  Vec3 w, pd;
  point_velocity(data, body, X.p, w, pd);
  to_reference(reference, X, w, pd);
  Vec6 out;
  out << w, pd;
  return out;
}

Vec6 frame_acceleration(const Model& model, const Data& data, int frame, const VecX& qdd, Reference reference,
                        bool classical) {
  check_frame(model, "frame_acceleration", frame);
  data.check(model, "frame_acceleration", "qdd", qdd.size(), model.nv);
  const int b = model.frame_body[frame];
  const Placement X = place(model, data, frame);
  Vec3 w, pd, alpha, pdd;
  point_velocity(data, b, X.p, w, pd);
  detail::point_acceleration(model, data, b, X.p, &qdd, alpha, pdd);
  Vec3 lin;
  if (classical) {
    // the body's point at the reference point: p itself, or the one at the origin for world
    lin = reference == Reference::World ? Vec3(pdd - alpha.cross(X.p) - w.cross(w.cross(X.p))) : pdd;
  } else {
    // d/dt (ṗ − ω × p) for world, d/dt (Rᵀ ṗ) = Rᵀ (p̈ − ω × ṗ) for local (and local_world_aligned)
    lin = reference == Reference::World ? Vec3(pdd - alpha.cross(X.p) - w.cross(pd)) : Vec3(pdd - w.cross(pd));
  }
  if (reference == Reference::Local) alpha = X.R.transpose() * alpha, lin = X.R.transpose() * lin;
  Vec6 out;
  out << alpha, lin;
  return out;
}

void frame_jacobian(const Model& model, const Data& data, int frame, Reference reference, MatX& J) {
  check_frame(model, "frame_jacobian", frame);
  point_columns(model, data, model.frame_body[frame], place(model, data, frame), reference, J);
}

void body_frame_jacobian(const Model& model, const Data& data, int body, const Placement& on_body, Reference reference,
                         MatX& J) {
  check_body(model, "body_frame_jacobian", body);
  point_columns(model, data, body, place_on(data, body, on_body), reference, J);
}

void frame_jacobian(const Model& model, Data& data, const VecX& q, int frame, Reference reference, MatX& J) {
  check_frame(model, "frame_jacobian", frame);
  update_frames_to(model, data, q, model.frame_body[frame]);
  point_columns(model, data, model.frame_body[frame], place(model, data, frame), reference, J);
}

void frame_jacobian_dot_times_v(const Model& model, const Data& data, int frame, Reference reference, Vec6& out) {
  check_frame(model, "frame_jacobian_dot_times_v", frame);
  body_frame_jacobian_dot_times_v(model, data, model.frame_body[frame], model.frame_placement[frame], reference, out);
}

void body_frame_jacobian_dot_times_v(const Model& model, const Data& data, int b, const Placement& on_body,
                                     Reference reference, Vec6& out) {
  check_body(model, "body_frame_jacobian_dot_times_v", b);
  const Placement X = place_on(data, b, on_body);
  Vec3 w, pd, alpha, pdd;
  point_velocity(data, b, X.p, w, pd);
  detail::point_acceleration(model, data, b, X.p, nullptr, alpha, pdd);
  switch (reference) {
    case Reference::LocalWorldAligned: break;                                    // d/dt [ω; ṗ]
    case Reference::Local: pdd = X.R.transpose() * (pdd - w.cross(pd)), alpha = X.R.transpose() * alpha; break;
    case Reference::World: pdd -= alpha.cross(X.p) + w.cross(pd); break;         // d/dt (ṗ − ω × p)
  }
  out << alpha, pdd;
}

void point_jacobian(const Model& model, const Data& data, int body, const Vec3& point, MatX& J) {
  check_body(model, "point_jacobian", body);
  J.setZero(3, model.nv);
  if (body < 0) return;
  const Vec3 p = Vec3(data.eta.col(body)) + data.R[body] * point;
  // ṗ = Σ_{j ≤ b} (u_k + g_k × (p − η_j)) v_k
  for (int j = body; j >= 0; j = model.parent[j]) {
    const Vec3 r = p - data.eta.col(j);
    for (int k = model.idx_v[j]; k < model.idx_v[j] + model.nv_i[j]; ++k)
      J.col(k) = data.G.col(k).tail<3>() + Vec3(data.G.col(k).head<3>()).cross(r);
  }
}

}  // namespace soadyn
