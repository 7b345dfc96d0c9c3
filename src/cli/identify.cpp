// soadyn identify SCENE.yaml --data RUN.h5 --parameters link2,link3 -o FITTED.yaml: the bodies'
// inertial parameters fitted to a logged motion (identify.hpp), with their standard errors and
// the directions the data cannot see, and the scene written with the fitted values.
#include "cli.hpp"

#include "soadyn/io/h5log.hpp"
#include "soadyn/sim/identify.hpp"
#include "soadyn/multibody/text.hpp"

#include <cmath>
#include <cstdio>

namespace soadyn::cli {

void add_identify(CLI::App& app, IdentifyCommand& o) {
  CLI::App* c = app.add_subcommand(
      "identify",
      "Fit some bodies' inertial parameters (mass, first moment m c, inertia about the body origin: 10 each)\n"
      "to a run file's motion, the other bodies held at the scene's values.  Least squares on the joint-torque\n"
      "regressor when the run logs q'' (/qdd), the torques being the scene's inputs at each sample; otherwise\n"
      "Gauss-Newton on the logged q, qd with CVODES sensitivities.  Prints each parameter with its standard\n"
      "error and the combinations the data cannot identify (held at the scene's values), and writes the scene\n"
      "with the fitted bodies' mass, com and inertia under `inertial:`.\n"
      "Exit status: 0 fitted, 2 bad input (scene, run file, --parameters, a fit that is no rigid body) or\n"
      "output refused (nothing written), 4 writing the output failed (an existing file is unchanged).");
  c->add_option("SCENE", o.scenario, "scenario (.yaml) or robot (.urdf) whose motion the run logged")->required();
  c->add_option("--data", o.data, "HDF5 run file (soadyn run, soadyn.simulate(output=...))")->required();
  c->add_option("--parameters", o.parameters, "comma-separated bodies to fit, or all")->required();
  c->add_option("-o,--output", o.output, "fitted scenario to write (.yaml); default: none");
  c->add_option("--method", o.method, "auto (least squares when the run logs /qdd) | least-squares | gauss-newton")
      ->transform(one_of({"auto", "least-squares", "gauss-newton"}));
  c->add_option("--rank-tolerance", o.rank_tolerance,
                "singular values of the column-scaled regressor below this times the largest count as zero (default 1e-8)");
  c->add_option("--max-iterations", o.max_iterations, "Gauss-Newton iterations at most (default 20)");
  c->add_option("--window", o.window, "Gauss-Newton: s simulated from each logged state (default 0.1)");
  c->add_flag("--force", o.force, "replace an output that is not a scenario soadyn identify wrote (never an input)");
  c->add_flag("-q,--quiet", o.quiet, "print nothing");
}

int run_identify(const IdentifyCommand& o) {
  // everything is checked and fitted before any file is touched
  const Scenario sc = load_with_options(o.scenario, {});
  soadyn::IdentifyOptions options;
  for (size_t at = 0; at <= o.parameters.size();) {
    const size_t comma = std::min(o.parameters.find(',', at), o.parameters.size());
    if (comma > at) options.bodies.push_back(o.parameters.substr(at, comma - at));
    at = comma + 1;
  }
  options.method = *parse_identify_method(o.method);
  options.rank_tolerance = o.rank_tolerance;
  if (o.max_iterations < 1) throw Error("--max-iterations: expected a whole number >= 1, got " + std::to_string(o.max_iterations));
  options.max_iterations = o.max_iterations;
  options.window = o.window;
  // the output first (before the data is read and fitted): never onto a file the fit reads (the
  // scenario, its robot and includes, the data), forced or not
  OutputTarget target = OutputTarget::New;
  if (!o.output.empty()) {
    std::vector<std::string> inputs = sc.files;
    inputs.insert(inputs.end(), {o.scenario, o.data});
    target = check_outputs({{o.output, OutputKind::Scenario}}, inputs, o.force).at(0);
  }
  const Measurements data = read_measurements(o.data, sc.model);
  const IdentifyResult r = identify(sc, data, options);
  const std::string text = o.output.empty() ? std::string() : fitted_scenario_text(sc, r, o.output);

  if (!o.quiet) {
    std::printf("scenario     %s\ndata         %s (%lld samples)\n", sc.path.c_str(), o.data.c_str(),
                static_cast<long long>(data.t.size()));
    std::printf("method       %s%s\n", r.method.c_str(),
                r.method == "gauss-newton" ? (" (" + std::to_string(r.iterations) + " iterations)").c_str() : "");
    std::printf("equations    %d, parameters %zu, rank %d (singular values of the column-scaled system below %g of the largest count as zero)\n",
                r.rows, r.names.size(), r.rank, options.rank_tolerance);
    std::printf("residual     RMS %.6g at the scene's values, %.6g fitted; sigma^2 %.6g\n", r.rms_prior, r.rms_fitted, r.sigma2);
    std::printf("%-22s %16s %16s %12s  %s\n", "parameter", "scene", "fitted", "std. error", "unit");
    for (size_t k = 0; k < r.names.size(); ++k)
      std::printf("%-22s %16.9g %16.9g %12.3g  %s\n", printable(r.names[k]).c_str(), r.prior(Eigen::Index(k)),
                  r.fitted(Eigen::Index(k)), r.standard_error(Eigen::Index(k)), r.units[k].c_str());
    if (r.unidentifiable.cols() > 0) {
      std::printf("not identifiable from this data (held at the scene's values), %lld directions:\n",
                  static_cast<long long>(r.unidentifiable.cols()));
      for (int k = 0; k < int(r.unidentifiable.cols()); ++k) std::printf("  %s\n", describe_direction(r, k).c_str());
    }
  }
  if (!o.output.empty()) {
    try {
      TextWriter w(o.output, target);
      w.write(text);
      w.commit();
    } catch (const IoError& e) {
      std::fprintf(stderr, "soadyn: error: %s\n", e.what());
      return 4;
    }
    if (!o.quiet) std::printf("output       %s\n", o.output.c_str());
  }
  return 0;
}

}  // namespace soadyn::cli
