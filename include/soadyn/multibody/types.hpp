// Basic types and the note's notation.
//
// Spatial vectors are [ω; v], angular first, in inertial coordinates (the note's convention).
// Stacked vectors (the note's y = [y_1, ..., y_N]) are stored as 6×N matrices, column i = body i.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <stdexcept>
#include <string>

namespace soadyn {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;
using Mat3X = Eigen::Matrix<double, 3, Eigen::Dynamic>;
using Mat6X = Eigen::Matrix<double, 6, Eigen::Dynamic>;
// A joint's motion subspace G_i: 6 rows, at most 6 columns, never on the heap.
using Mat6G = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 6>;
using MatGG = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
using VecG = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1>;

// ã: the skew matrix with ã b = a × b.
inline Mat3 skew(const Vec3& a) {
  Mat3 m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}

// A file a model was compiled from, as it was handed to the compiler: the name it was given and its
// bytes (an MJCF model's main text, <include>s and assets, mjcf.hpp; stored with a run, h5log.hpp
// /model_files, so that soadyn view compiles the model from them and never from the disk).
struct ModelFile {
  std::string name, data;
  bool operator==(const ModelFile&) const = default;
};

// Every error soadyn reports: what went wrong, where, what was expected and what was got.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A model refused by Model::build; `spec` is the index of the offending body in the spec list.
class ModelError : public Error {
 public:
  ModelError(int spec, const std::string& where, const std::string& detail)
      : Error(where + ": " + detail), spec(spec), detail(detail) {}
  int spec;            // index in the spec list
  std::string detail;  // "field: expected …, got …", without the body's name
};

}  // namespace soadyn
