// soadyn._identify: identify.hpp's fit for soadyn.identify (soadyn/__init__.py), from a run file or
// from arrays.
#include "common.hpp"

#include "soadyn/sim/identify.hpp"
#include "soadyn/multibody/text.hpp"

#include <optional>

namespace soadyn::python {

namespace {

// a T × cols float64 array as a MatX (None or an empty array: 0 × 0)
MatX matrix_arg(const char* what, const std::optional<py::array_t<double, py::array::forcecast>>& a) {
  if (!a || a->size() == 0) return MatX();
  return read_matrix("identify", what, *a);
}

}  // namespace

void bind_identify(py::module_& m) {
  m.def("_identify", [](const Scenario& sc, const std::optional<std::string>& path,
                        const std::optional<py::array_t<double, py::array::forcecast>>& t,
                        const std::optional<py::array_t<double, py::array::forcecast>>& q,
                        const std::optional<py::array_t<double, py::array::forcecast>>& v,
                        const std::optional<py::array_t<double, py::array::forcecast>>& qdd,
                        const std::optional<py::array_t<double, py::array::forcecast>>& tau,
                        const std::vector<std::string>& bodies, const std::string& method, double rank_tolerance,
                        int max_iterations, double window, const std::string& output) {
        IdentifyOptions o;
        o.bodies = bodies;
        const auto how = parse_identify_method(method);
        if (!how)
          throw py::value_error("identify: method: expected 'auto', 'least-squares' or 'gauss-newton', got '" + method + "'" +
                                did_you_mean(method, {"auto", "least-squares", "gauss-newton"}));
        o.method = *how;
        o.rank_tolerance = rank_tolerance;
        o.max_iterations = max_iterations;
        o.window = window;
        Measurements d;
        if (path) {
          d = read_measurements(*path, sc.model);
        } else {
          d.path = "<arrays>";
          if (t) {
            if (t->ndim() != 1) throw Error("identify: t: expected a 1-D array of times");
            d.t.resize(t->shape(0));
            for (py::ssize_t k = 0; k < t->shape(0); ++k) d.t(k) = t->at(k);
          }
          d.q = matrix_arg("q", q);
          d.v = matrix_arg("v", v);
          d.qdd = matrix_arg("qdd", qdd);
        }
        d.tau = matrix_arg("tau", tau);
        IdentifyResult r;
        {
          py::gil_scoped_release release;
          r = identify(sc, d, o);
        }
        std::vector<std::string> directions;
        for (int k = 0; k < int(r.unidentifiable.cols()); ++k) directions.push_back(describe_direction(r, k));
        const std::string text = fitted_scenario_text(sc, r, output.empty() ? sc.path : output);
        return py::dict("method"_a = r.method, "names"_a = r.names, "units"_a = r.units, "prior"_a = owned(VecX(r.prior)),
                        "fitted"_a = owned(VecX(r.fitted)), "standard_errors"_a = owned(VecX(r.standard_error)),
                        "rows"_a = r.rows, "rank"_a = r.rank, "iterations"_a = r.iterations,
                        "singular_values"_a = owned(VecX(r.singular_values)),
                        "unidentifiable"_a = owned(MatX(r.unidentifiable)), "unidentifiable_text"_a = directions,
                        "sigma2"_a = r.sigma2, "rms_prior"_a = r.rms_prior, "rms_fitted"_a = r.rms_fitted,
                        "model"_a = r.model, "scenario_text"_a = text);
      },
      "scene"_a, "path"_a, "t"_a, "q"_a, "v"_a, "qdd"_a, "tau"_a, "parameters"_a, "method"_a, "rank_tolerance"_a,
      "max_iterations"_a, "window"_a, "output"_a, "identify.hpp's fit; soadyn.identify wraps it");
}

}  // namespace soadyn::python
