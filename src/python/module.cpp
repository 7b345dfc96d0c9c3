// soadyn._soadyn: the compiled part of the Python package (soadyn/__init__.py re-exports it).
#include "common.hpp"

#include "soadyn/io/version.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

namespace soadyn::python {

PyObject* error_type = nullptr;

// NaN or ±inf in an argument would come back as NaN everywhere: refused, naming the entry
[[noreturn]] static void not_finite(const char* where, const char* what, const double* x) {
  int k = 0;
  while (std::isfinite(x[k])) ++k;
  char value[32];
  std::snprintf(value, sizeof value, "%g", x[k]);
  throw Error(std::string(where) + ": " + what + "[" + std::to_string(k) + "] = " + value + ": expected a finite number");
}

// out[k] = the double at src + k·stride, k < n, and whether any was NaN or ±inf: one pass, the test
// on the bits (an exponent of all ones; Eigen's allFinite forms x − x first), no call for a few
// entries (a memcpy call and a second pass cost about as much as a 7-vector's whole copy)
static inline bool copy_finite(const char* src, Py_ssize_t stride, int n, double* out) {
  constexpr std::uint64_t exponent = 0x7ff0000000000000ull;
  std::uint64_t bad = 0;
  for (int k = 0; k < n; ++k, src += stride) {
    std::uint64_t bits;
    std::memcpy(&bits, src, sizeof bits);
    std::memcpy(out + k, &bits, sizeof bits);
    bad |= std::uint64_t((bits & exponent) == exponent);
  }
  return bad != 0;
}

void read_vector(const Model& model, const Data& data, const char* where, const char* what, py::handle h,
                 int expected, VecX& out) {
  // fast path: a 1-D float64 ndarray in native byte order, read where it lies
  const auto& api = py::detail::npy_api::get();
  if (api.PyArray_Check_(h.ptr())) {
    const auto* p = py::detail::array_proxy(h.ptr());
    const auto* descr = py::detail::array_descriptor_proxy(p->descr);
    if (p->nd == 1 && descr->type_num == py::detail::npy_api::NPY_DOUBLE_ && descr->byteorder != '>') {
      // the checks of Data::check written out, so that the call is made only to throw
      if (p->dimensions[0] != expected || data.G.cols() != model.nv || int(data.R.size()) != model.nbodies)
        data.check(model, where, what, p->dimensions[0], expected);
      const bool bad = p->strides[0] == sizeof(double) ? copy_finite(p->data, sizeof(double), expected, out.data())
                                                        : copy_finite(p->data, p->strides[0], expected, out.data());
      if (bad) not_finite(where, what, out.data());
      return;
    }
  }
  const ArrayIn a = ArrayIn::ensure(h);  // numpy's conversion: lists, other dtypes, byte orders
  if (!a)
    throw py::type_error(std::string(where) + ": " + what + ": expected numbers, got " +
                         std::string(py::str(py::type::handle_of(h).attr("__name__"))));
  if (a.ndim() != 1) {
    std::string shape;
    for (py::ssize_t k = 0; k < a.ndim(); ++k) shape += (k ? ", " : "") + std::to_string(a.shape(k));
    throw Error(std::string(where) + ": " + what + ": expected a 1-D array of " + std::to_string(expected) +
                " entries, got shape (" + shape + ")");
  }
  data.check(model, where, what, a.shape(0), expected);
  // element by element: any stride, no temporary
  if (copy_finite(reinterpret_cast<const char*>(a.data()), a.strides(0), expected, out.data()))
    not_finite(where, what, out.data());
}

VecX read_vector(const char* where, const char* what, const ArrayIn& a, int expected) {
  if (a.ndim() != 1 || a.shape(0) != expected)
    throw Error(std::string(where) + ": " + what + ": expected a 1-D array of " + std::to_string(expected) +
                " entries, got " + (a.ndim() == 1 ? std::to_string(a.shape(0)) + " entries" : std::to_string(a.ndim()) + " dimensions"));
  VecX out(expected);
  if (copy_finite(reinterpret_cast<const char*>(a.data()), a.strides(0), expected, out.data()))
    not_finite(where, what, out.data());
  return out;
}

MatX read_matrix(const char* where, const char* what, const ArrayIn& a) {
  if (!a || a.ndim() != 2)
    throw Error(std::string(where) + ": " + what + ": expected a 2-D array (samples × columns)");
  MatX out(a.shape(0), a.shape(1));
  const auto u = a.unchecked<2>();
  for (py::ssize_t r = 0; r < a.shape(0); ++r)
    for (py::ssize_t c = 0; c < a.shape(1); ++c) out(r, c) = u(r, c);
  return out;
}

py::array owned(std::vector<double>&& values, std::vector<py::ssize_t> shape) {
  auto* keep = new std::vector<double>(std::move(values));
  py::capsule base(keep, [](void* p) { delete static_cast<std::vector<double>*>(p); });
  return py::array(py::dtype::of<double>(), std::move(shape), {}, keep->data(), base);
}

py::array owned(VecX&& v) {
  auto* keep = new VecX(std::move(v));
  py::capsule base(keep, [](void* p) { delete static_cast<VecX*>(p); });
  return py::array(py::dtype::of<double>(), {keep->size()}, {}, keep->data(), base);
}

py::array owned(MatX&& m) {
  auto* keep = new MatX(std::move(m));
  py::capsule base(keep, [](void* p) { delete static_cast<MatX*>(p); });
  const py::ssize_t s = sizeof(double);
  return py::array(py::dtype::of<double>(), {keep->rows(), keep->cols()}, {s, s * keep->rows()}, keep->data(), base);
}

py::array owned(SampleRows&& m, std::vector<py::ssize_t> shape) {
  auto* keep = new SampleRows(std::move(m));
  py::capsule base(keep, [](void* p) { delete static_cast<SampleRows*>(p); });
  return py::array(py::dtype::of<double>(), std::move(shape), {}, keep->data(), base);
}

void set_python_error() {
  try {
    throw;
  } catch (py::error_already_set& e) {
    e.restore();
  } catch (const Error& e) {
    PyErr_SetString(error_type, e.what());
  } catch (const py::builtin_exception& e) {
    e.set_error();
  } catch (const std::bad_alloc&) {
    PyErr_NoMemory();
  } catch (const std::exception& e) {
    PyErr_SetString(PyExc_RuntimeError, e.what());
  }
}

namespace {

// a read-only view of memory inside `base`'s Data
py::array view(const py::capsule& base, double* ptr, std::vector<py::ssize_t> shape, std::vector<py::ssize_t> strides) {
  for (auto& st : strides) st *= py::ssize_t(sizeof(double));
  py::array a(py::dtype::of<double>(), std::move(shape), std::move(strides), ptr, base);
  a.attr("setflags")("write"_a = false);
  return a;
}

}  // namespace

PyData::PyData(const Model& model)
    : data(std::make_shared<Data>(model)), nq(model.nq), nv(model.nv), nbodies(model.nbodies), q(nq), v(nv), x(nv),
      kept_M(nv, nv), kept_bias(nv), kept_qdd(nv), kept_tau(nv) {
  auto* keep = new std::shared_ptr<Data>(data);
  py::capsule base(keep, [](void* p) { delete static_cast<std::shared_ptr<Data>*>(p); });
  Data& D = *data;
  const py::ssize_t n = nbodies;
  M = view(base, D.M.data(), {nv, nv}, {1, nv});  // column-major; symmetric anyway
  bias = view(base, D.bias.data(), {nv}, {1});
  tau = view(base, D.tau.data(), {nv}, {1});
  qdd = view(base, D.qdd.data(), {nv}, {1});
  // std::vector<Mat3>: N column-major 3×3 blocks back to back
  static_assert(sizeof(Mat3) == 9 * sizeof(double));
  R = view(base, n ? D.R[0].data() : nullptr, {n, 3, 3}, {9, 1, 3});
  // 3×N and 6×N column-major stacks read as N×3 and N×6 rows (row i = body i)
  eta = view(base, D.eta.data(), {n, 3}, {3, 1});
  d = view(base, D.d.data(), {n, 3}, {3, 1});
  s = view(base, D.s.data(), {n, 3}, {3, 1});
  r = view(base, D.r.data(), {n, 3}, {3, 1});
  V = view(base, D.V.data(), {n, 6}, {6, 1});
  Vbar = view(base, D.Vbar.data(), {n, 6}, {6, 1});
  G = view(base, D.G.data(), {6, nv}, {1, 6});
}

DerivativeData& PyData::derivative_data(const Model& model) {
  if (nv != model.nv || nbodies != model.nbodies) check(model, "derivatives");  // throws
  if (derivatives) return *derivatives;
  auto dd = std::make_shared<DerivativeData>(model);
  auto* keep = new std::shared_ptr<DerivativeData>(dd);
  py::capsule base(keep, [](void* p) { delete static_cast<std::shared_ptr<DerivativeData>*>(p); });
  // column-major nv×nv
  dtau_dq = view(base, dd->dtau_dq.data(), {nv, nv}, {1, nv});
  dtau_dv = view(base, dd->dtau_dv.data(), {nv, nv}, {1, nv});
  dqdd_dq = view(base, dd->dqdd_dq.data(), {nv, nv}, {1, nv});
  dqdd_dv = view(base, dd->dqdd_dv.data(), {nv, nv}, {1, nv});
  dqdd_dtau = view(base, dd->Minv.data(), {nv, nv}, {1, nv});
  id_result = py::make_tuple(dtau_dq, dtau_dv);
  fd_result = py::make_tuple(dqdd_dq, dqdd_dv, dqdd_dtau);
  // minverse's own nv×nv
  minverse_result = std::make_shared<MatX>(MatX::Zero(nv, nv));
  auto* own = new std::shared_ptr<MatX>(minverse_result);
  py::capsule own_base(own, [](void* p) { delete static_cast<std::shared_ptr<MatX>*>(p); });
  Minv = view(own_base, minverse_result->data(), {nv, nv}, {1, nv});
  derivatives = std::move(dd);
  return *derivatives;
}

}  // namespace soadyn::python

PYBIND11_MODULE(_soadyn, m) {
  namespace sp = soadyn::python;
  m.doc() = "The compiled part of soadyn; import soadyn instead.";
  m.attr("__version__") = soadyn::version();
  // soadyn.Error is a ValueError: bad input, with the command line's message (soadyn::Error and
  // every error derived from it)
  static sp::py::exception<soadyn::Error> error(m, "Error", PyExc_ValueError);
  sp::error_type = error.ptr();
  error.doc() = "Bad input (a file, a field, a vector's size, a setting), with the command line's message: "
                "file:line:column: field: expected …, got ….";
  sp::py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const soadyn::Error& e) {
      error(e.what());
    }
  });
  sp::bind_model(m);
  sp::bind_algorithms(m);
  sp::bind_simulate(m);
  sp::bind_batch(m);
  sp::bind_frames(m);
  sp::bind_regressor(m);
  sp::bind_adjoint(m);
  sp::bind_pickle(m);
  sp::bind_identify(m);
  sp::bind_run_file(m);
  sp::bind_loops(m);
}
