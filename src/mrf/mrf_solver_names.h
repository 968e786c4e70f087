#pragma once
// The MRF solvers' names as the options' help texts list them: one copy for --Mrf.solver and
// --OrientationStereo.mrf_solver (whose public header includes this one and not src/mrf/mrf.h).
// MrfSolverOptions.NamesRoundTripAndCheck checks that it names every MrfSolverType.

namespace hairmvs {

inline constexpr char kMrfSolverNameList[] =
    "graph_cuts | semi_global | semi_global_cpu | belief_propagation | belief_propagation_cpu | "
    "icm | winner_take_all";

}  // namespace hairmvs
