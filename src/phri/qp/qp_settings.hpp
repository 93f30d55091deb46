#pragma once
// phri::QpSettings: tolerances and limits of QpSolver, set once at setup.

namespace phri {

struct QpSettings {
  // Maximum active-set changes per solve; <= 0 means 10 * (n + m_eq + m_in) + 10.
  int max_iterations = 0;
  // A row is violated when its distance to the feasible side (rows are normalised to unit
  // length) exceeds feasibility_tolerance * (1 + |x|_inf + |bound|).
  double feasibility_tolerance = 1e-10;
  // A new constraint normal n is taken as linearly dependent on the active ones when the part of
  // J'n outside the active span is below this fraction of |J'n|.
  double dependence_tolerance = 1e-10;
  // Bounds at or beyond +-infinity are absent.
  double infinity = 1e20;
};

}  // namespace phri
