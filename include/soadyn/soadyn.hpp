// soadyn: every public header, layer by layer (include/soadyn/README.md maps them).
//
//   multibody  the model and its data: joint kinds, bodies, inertias
//   algorithm  the sweeps on them: kinematics, 𝓜, bias, RNEA, forward dynamics, derivatives, …
//   sim        simulation: settings, integrators, controllers, limits, sensitivities, identification
//   io         files: scenarios, URDF, MJCF, run files (HDF5) and the one-call simulate(scenario)
#pragma once

#include "soadyn/multibody/configuration.hpp"
#include "soadyn/multibody/data.hpp"
#include "soadyn/multibody/inertia.hpp"
#include "soadyn/multibody/joint.hpp"
#include "soadyn/multibody/joint_model.hpp"
#include "soadyn/multibody/joint_space.hpp"
#include "soadyn/multibody/model.hpp"
#include "soadyn/multibody/text.hpp"
#include "soadyn/multibody/types.hpp"

#include "soadyn/algorithm/algorithms.hpp"
#include "soadyn/algorithm/batch.hpp"
#include "soadyn/algorithm/derivatives.hpp"
#include "soadyn/algorithm/fd_method.hpp"
#include "soadyn/algorithm/frames.hpp"
#include "soadyn/algorithm/hybrid.hpp"
#include "soadyn/algorithm/loops.hpp"
#include "soadyn/algorithm/inputs.hpp"
#include "soadyn/algorithm/kinematics.hpp"
#include "soadyn/algorithm/operators.hpp"
#include "soadyn/algorithm/regressor.hpp"
#include "soadyn/algorithm/table.hpp"

#include "soadyn/sim/adjoint.hpp"
#include "soadyn/sim/controller.hpp"
#include "soadyn/sim/identify.hpp"
#include "soadyn/sim/integrators.hpp"
#include "soadyn/sim/limits.hpp"
#include "soadyn/sim/newton_solver.hpp"
#include "soadyn/sim/rollout.hpp"
#include "soadyn/sim/scenario.hpp"
#include "soadyn/sim/sensitivity.hpp"
#include "soadyn/sim/settings.hpp"
#include "soadyn/sim/system.hpp"
#include "soadyn/sim/simulate.hpp"
#include "soadyn/sim/trajectory.hpp"

#include "soadyn/io/h5log.hpp"
#include "soadyn/io/input_file.hpp"
#include "soadyn/io/mjcf.hpp"
#include "soadyn/io/output_file.hpp"
#include "soadyn/io/run.hpp"
#include "soadyn/io/run_file.hpp"
#include "soadyn/io/scenario_file.hpp"
#include "soadyn/io/table_file.hpp"
#include "soadyn/io/version.hpp"
