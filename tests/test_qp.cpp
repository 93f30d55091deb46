// ctest-labels: unit
// QpSolver against independent references: the KKT conditions, brute-force enumeration of active
// sets with a plain Eigen solve of each KKT system, closed forms; plus bad input and allocations.
#include <phri/qp/qp_solver.hpp>

#include <allocation_counter.hpp>
#include <qp_kkt.hpp>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <vector>


namespace phri {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kInf = std::numeric_limits<double>::infinity();

// The sanitizer build runs the same checks on fewer random problems.
#ifdef NDEBUG
constexpr int kScale = 1;
#else
constexpr int kScale = 10;
#endif

// ------------------------------------------------------------------------------------ generators

struct Rng {
  std::mt19937_64 engine;
  explicit Rng(std::uint64_t seed) : engine(seed) {}
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(engine); }
  double normal() { return std::normal_distribution<double>(0.0, 1.0)(engine); }
  int integer(int a, int b) { return std::uniform_int_distribution<int>(a, b)(engine); }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }
  MatrixXd gaussian(Index rows, Index cols) {
    MatrixXd m(rows, cols);
    for (Index j = 0; j < cols; ++j)
      for (Index i = 0; i < rows; ++i) m(i, j) = normal();
    return m;
  }
  VectorXd gaussian(Index size) { return gaussian(size, 1).col(0); }
};

// Q diag(10^[0, log10_cond]) Q' with a random orthogonal Q.
MatrixXd random_spd(Rng& rng, Index n, double log10_cond) {
  const MatrixXd q = Eigen::HouseholderQR<MatrixXd>(rng.gaussian(n, n)).householderQ();
  VectorXd eig(n);
  for (Index i = 0; i < n; ++i) {
    eig(i) = std::pow(10.0, n == 1 ? 0.0 : log10_cond * static_cast<double>(i) / static_cast<double>(n - 1));
  }
  MatrixXd h = q * eig.asDiagonal() * q.transpose();
  return 0.5 * (h + h.transpose());
}

struct Shape {
  Index n;
  Index m_eq;
  Index m_in;
};

// A problem feasible by construction around a random point x_f; the gradient pulls the
// unconstrained minimum away from it so that constraints become active.
QpProblem random_problem(Rng& rng, const Shape& s, double log10_cond, bool with_bounds, double gradient_scale) {
  QpProblem p;
  p.resize(s.n, s.m_eq, s.m_in);
  p.H = random_spd(rng, s.n, log10_cond) * std::pow(10.0, rng.uniform(-2.0, 2.0));
  const VectorXd x_f = rng.gaussian(s.n);
  p.g = gradient_scale * rng.gaussian(s.n).cwiseProduct(p.H.diagonal());
  p.A_eq = rng.gaussian(s.m_eq, s.n);
  p.b_eq = p.A_eq * x_f;
  p.A = rng.gaussian(s.m_in, s.n);
  for (Index i = 0; i < s.m_in; ++i) {
    if (i > 0 && rng.chance(0.05)) p.A.row(i) = rng.uniform(0.1, 3.0) * p.A.row(rng.integer(0, static_cast<int>(i - 1)));
    if (rng.chance(0.03)) p.A.row(i).setZero();
    const double v = p.A.row(i).dot(x_f);
    const int kind = rng.integer(0, 9);
    p.l(i) = v - rng.uniform(0.0, 2.0);
    p.u(i) = v + rng.uniform(0.0, 2.0);
    if (kind <= 1) p.l(i) = kind == 0 ? -kInf : -1e21;      // upper side only
    if (kind == 2 || kind == 3) p.u(i) = kind == 2 ? kInf : 1e22;  // lower side only
    if (kind == 4) p.l(i) = p.u(i) = v;                    // equality written as a row
    if (kind == 5 && rng.chance(0.2)) {                    // free row
      p.l(i) = -kInf;
      p.u(i) = kInf;
    }
  }
  if (with_bounds) {
    for (Index j = 0; j < s.n; ++j) {
      p.lb(j) = rng.chance(0.25) ? -kInf : x_f(j) - rng.uniform(0.0, 1.5);
      p.ub(j) = rng.chance(0.25) ? kInf : x_f(j) + rng.uniform(0.0, 1.5);
      if (rng.chance(0.03)) p.lb(j) = p.ub(j) = x_f(j);
    }
  }
  return p;
}

// ------------------------------------------------------------------------------------ references

using test::Kkt;
using test::kkt_residuals;
using test::lower_of;
using test::upper_of;

double objective(const QpProblem& p, const VectorXd& x) {
  const MatrixXd h = p.H.selfadjointView<Eigen::Lower>();
  return 0.5 * x.dot(h * x) + p.g.dot(x);
}

// Every constraint as a dense row with its two sides (bounds become unit rows).
struct DenseRows {
  MatrixXd a;
  VectorXd lo;
  VectorXd hi;
  Index m_eq = 0;
};

DenseRows dense_rows(const QpProblem& p) {
  const Index n = p.g.size();
  DenseRows d;
  d.m_eq = p.A_eq.rows();
  std::vector<Index> bounded;
  for (Index j = 0; j < n; ++j) {
    if (std::isfinite(lower_of(p.lb, j)) || std::isfinite(upper_of(p.ub, j))) bounded.push_back(j);
  }
  const Index m = d.m_eq + p.A.rows() + static_cast<Index>(bounded.size());
  d.a.setZero(m, n);
  d.lo.setZero(m);
  d.hi.setZero(m);
  d.a.topRows(d.m_eq) = p.A_eq;
  d.lo.head(d.m_eq) = p.b_eq;
  d.hi.head(d.m_eq) = p.b_eq;
  for (Index i = 0; i < p.A.rows(); ++i) {
    d.a.row(d.m_eq + i) = p.A.row(i);
    d.lo(d.m_eq + i) = lower_of(p.l, i);
    d.hi(d.m_eq + i) = upper_of(p.u, i);
  }
  for (std::size_t b = 0; b < bounded.size(); ++b) {
    const Index row = d.m_eq + p.A.rows() + static_cast<Index>(b);
    d.a(row, bounded[b]) = 1.0;
    d.lo(row) = lower_of(p.lb, bounded[b]);
    d.hi(row) = upper_of(p.ub, bounded[b]);
  }
  return d;
}

// Smallest objective over all active sets whose equality-constrained minimiser (closed form, one
// LU solve of the KKT matrix) is feasible. The optimum has a linearly independent active set, so
// it is among them. Returns +inf when no candidate is feasible.
double brute_force_optimum(const QpProblem& p, VectorXd* best_x = nullptr) {
  const Index n = p.g.size();
  const DenseRows d = dense_rows(p);
  const Index m = d.a.rows();
  const MatrixXd h = p.H.selfadjointView<Eigen::Lower>();
  std::vector<int> choice(static_cast<std::size_t>(m), 0);  // 0 inactive, 1 lower, 2 upper
  double best = kInf;
  const auto feasible = [&](const VectorXd& x) {
    for (Index i = 0; i < m; ++i) {
      const double v = d.a.row(i).dot(x);
      const double scale = 1.0 + d.a.row(i).cwiseAbs().dot(x.cwiseAbs());
      if (v < d.lo(i) - 1e-10 * (scale + std::abs(d.lo(i)))) return false;
      if (v > d.hi(i) + 1e-10 * (scale + std::abs(d.hi(i)))) return false;
    }
    return true;
  };
  while (true) {
    std::vector<Index> active;
    std::vector<double> target;
    for (Index i = 0; i < m; ++i) {
      if (i < d.m_eq) {
        active.push_back(i);
        target.push_back(d.lo(i));
      } else if (choice[static_cast<std::size_t>(i)] == 1) {
        active.push_back(i);
        target.push_back(d.lo(i));
      } else if (choice[static_cast<std::size_t>(i)] == 2) {
        active.push_back(i);
        target.push_back(d.hi(i));
      }
    }
    const Index k = static_cast<Index>(active.size());
    if (k <= n) {
      // KKT system, symmetrically scaled (unit diagonal of H, unit rows of N) so that the rank
      // test of the LU sees balanced pivots even when H is ill-conditioned.
      VectorXd scale(n + k);
      for (Index j = 0; j < n; ++j) scale(j) = 1.0 / std::sqrt(h(j, j));
      MatrixXd kkt = MatrixXd::Zero(n + k, n + k);
      VectorXd rhs(n + k);
      kkt.topLeftCorner(n, n) = h;
      rhs.head(n) = -p.g;
      for (Index r = 0; r < k; ++r) {
        kkt.block(n + r, 0, 1, n) = d.a.row(active[static_cast<std::size_t>(r)]);
        kkt.block(0, n + r, n, 1) = d.a.row(active[static_cast<std::size_t>(r)]).transpose();
        rhs(n + r) = target[static_cast<std::size_t>(r)];
        const double row_norm = d.a.row(active[static_cast<std::size_t>(r)]).cwiseProduct(scale.head(n).transpose()).norm();
        scale(n + r) = row_norm > 0.0 ? 1.0 / row_norm : 1.0;
      }
      kkt = scale.asDiagonal() * kkt * scale.asDiagonal();
      rhs = scale.cwiseProduct(rhs);
      Eigen::FullPivLU<MatrixXd> lu(kkt);
      if (lu.isInvertible()) {
        // Two steps of refinement make the constraint rows exact to their own roundoff, which the
        // plain solve leaves at the size of the gradient rows' roundoff.
        VectorXd sol = lu.solve(rhs);
        for (int step = 0; step < 2; ++step) sol += lu.solve(rhs - kkt * sol);
        sol = scale.cwiseProduct(sol);
        const VectorXd x = sol.head(n);
        if (feasible(x)) {
          const double f = objective(p, x);
          if (f < best) {
            best = f;
            if (best_x) *best_x = x;
          }
        }
      }
    }
    // Next assignment: odometer over the sides each row actually has.
    Index i = d.m_eq;
    for (; i < m; ++i) {
      int& c = choice[static_cast<std::size_t>(i)];
      const bool has_lo = std::isfinite(d.lo(i));
      const bool has_hi = std::isfinite(d.hi(i)) && d.hi(i) != d.lo(i);
      do {
        c = (c + 1) % 3;
      } while ((c == 1 && !has_lo) || (c == 2 && !has_hi));
      if (c != 0) break;
    }
    if (i == m) break;
  }
  return best;
}

void expect_kkt(const QpProblem& p, const QpSolver& s, double tol, const std::string& what) {
  const Kkt r = kkt_residuals(p, s);
  EXPECT_LE(r.stationarity, tol) << what;
  EXPECT_LE(r.primal, tol) << what;
  EXPECT_LE(r.dual, tol) << what;
  EXPECT_LE(r.complementarity, tol) << what;
}

QpSolver solver_for(const QpProblem& p) {
  return QpSolver(p.g.size(), p.A_eq.rows(), p.A.rows());
}

// ------------------------------------------------------------------------------------ KKT

TEST(QpSolver, KktOnRandomFeasibleProblems) {
  Rng rng(20240601);
  const int count = 10000 / kScale;
  Kkt worst;
  int max_iterations = 0;
  for (int t = 0; t < count; ++t) {
    const Index n = rng.integer(1, 30);
    const bool bounds = rng.chance(0.7);
    const Index m_max = 60 - (bounds ? n : 0);
    const Index m_eq = rng.chance(0.3) ? rng.integer(0, static_cast<int>(std::min<Index>(n, 5))) : 0;
    const Index m_in = rng.integer(0, static_cast<int>(m_max - m_eq));
    const QpProblem p = random_problem(rng, {n, m_eq, m_in}, rng.uniform(0.0, 4.0), bounds, rng.uniform(0.0, 20.0));
    QpSolver s = solver_for(p);
    ASSERT_EQ(s.solve(p), QpStatus::kOptimal) << "problem " << t;
    const Kkt r = kkt_residuals(p, s);
    worst.stationarity = std::max(worst.stationarity, r.stationarity);
    worst.primal = std::max(worst.primal, r.primal);
    worst.dual = std::max(worst.dual, r.dual);
    worst.complementarity = std::max(worst.complementarity, r.complementarity);
    max_iterations = std::max(max_iterations, s.iterations());
    ASSERT_LE(r.worst(), 1e-9) << "problem " << t << " n " << n << " m_eq " << m_eq << " m_in " << m_in;
  }
  std::cout << "[ KKT ] " << count << " problems, largest residuals: stationarity " << worst.stationarity
            << ", primal " << worst.primal << ", dual " << worst.dual << ", complementarity "
            << worst.complementarity << "; most iterations " << max_iterations << "\n";
  RecordProperty("largest_kkt_residual", std::to_string(worst.worst()));
}

// ------------------------------------------------------------------------------------ brute force

TEST(QpSolver, GlobalOptimumAgainstActiveSetEnumeration) {
  Rng rng(7);
  const int count = 600 / kScale;
  double worst = 0.0;
  for (int t = 0; t < count; ++t) {
    const Index n = rng.integer(1, 6);
    const bool bounds = rng.chance(0.6);
    const Index bound_rows = bounds ? std::min<Index>(n, 3) : 0;
    const Index m_eq = rng.chance(0.3) ? rng.integer(0, static_cast<int>(std::min<Index>(n - 1, 2))) : 0;
    const Index m_in = rng.integer(0, static_cast<int>(8 - bound_rows - m_eq));
    QpProblem p = random_problem(rng, {n, m_eq, m_in}, rng.uniform(0.0, 3.0), false, rng.uniform(1.0, 20.0));
    if (bounds) {  // at most 3 bounded variables keeps it within 8 rows
      for (Index j = 0; j < bound_rows; ++j) {
        p.lb(j) = rng.chance(0.2) ? -kInf : rng.uniform(-2.0, 0.0);
        p.ub(j) = rng.chance(0.2) ? kInf : rng.uniform(0.0, 2.0);
      }
      // Keep the construction point feasible: it is unknown here, so re-centre the rows on 0.
      for (Index i = 0; i < m_in; ++i) {
        if (std::isfinite(p.l(i)) && p.l(i) > -1e20) p.l(i) = std::min(p.l(i), 0.0);
        if (std::isfinite(p.u(i)) && p.u(i) < 1e20) p.u(i) = std::max(p.u(i), 0.0);
      }
      p.b_eq.setZero();
    }
    QpSolver s = solver_for(p);
    const QpStatus status = s.solve(p);
    VectorXd x_ref;
    const double f_ref = brute_force_optimum(p, &x_ref);
    if (!std::isfinite(f_ref)) {
      EXPECT_EQ(status, QpStatus::kInfeasible) << "problem " << t;
      continue;
    }
    ASSERT_EQ(status, QpStatus::kOptimal) << "problem " << t;
    const double rel = std::abs(s.objective() - f_ref) / std::max(1.0, std::abs(f_ref));
    worst = std::max(worst, rel);
    EXPECT_LE(rel, 1e-9) << "problem " << t << " solver " << s.objective() << " brute force " << f_ref;
    EXPECT_NEAR(s.objective(), objective(p, s.x()), 1e-9 * std::max(1.0, std::abs(f_ref)));
  }
  std::cout << "[ brute force ] " << count << " problems, largest relative objective gap " << worst << "\n";
}

// ------------------------------------------------------------------------------------ closed forms

TEST(QpSolver, NoConstraints) {
  Rng rng(1);
  for (Index n : {1, 2, 7, 30, 60}) {
    QpProblem p;
    p.resize(n, 0, 0);
    p.H = random_spd(rng, n, 3.0);
    p.g = rng.gaussian(n);
    QpSolver s(n, 0, 0);
    ASSERT_EQ(s.solve(p), QpStatus::kOptimal);
    const VectorXd x_ref = -p.H.llt().solve(p.g);
    EXPECT_LE((s.x() - x_ref).norm(), 1e-10 * (1.0 + x_ref.norm()));
    EXPECT_EQ(s.iterations(), 0);
    EXPECT_EQ(s.active_count(), 0);
  }
}

// Tolerances are relative: scaling the whole objective changes nothing but the multipliers.
TEST(QpSolver, ObjectiveScaleDoesNotMatter) {
  Rng rng(16);
  for (Index n : {3, 7, 12}) {
    const QpProblem base = random_problem(rng, {n, 1, 2 * n}, 2.0, true, 10.0);
    QpSolver reference = solver_for(base);
    ASSERT_EQ(reference.solve(base), QpStatus::kOptimal);
    for (double scale : {1e-20, 1e-8, 1e8, 1e20}) {
      QpProblem p = base;
      p.H *= scale;
      p.g *= scale;
      QpSolver s = solver_for(p);
      ASSERT_EQ(s.solve(p), QpStatus::kOptimal) << n << " " << scale;
      EXPECT_LE((s.x() - reference.x()).norm(), 1e-9 * (1.0 + reference.x().norm())) << n << " " << scale;
      expect_kkt(p, s, 1e-9, "scaled objective");
    }
  }
}

TEST(QpSolver, EqualityOnly) {
  Rng rng(2);
  for (Index n : {1, 3, 7, 20}) {
    for (Index m_eq = 1; m_eq <= n; m_eq += std::max<Index>(1, n / 3)) {
      QpProblem p;
      p.resize(n, m_eq, 0);
      p.H = random_spd(rng, n, 2.0);
      p.g = rng.gaussian(n);
      p.A_eq = rng.gaussian(m_eq, n);
      p.b_eq = rng.gaussian(m_eq);
      QpSolver s(n, m_eq, 0);
      ASSERT_EQ(s.solve(p), QpStatus::kOptimal);
      MatrixXd kkt = MatrixXd::Zero(n + m_eq, n + m_eq);
      kkt << p.H, p.A_eq.transpose(), p.A_eq, MatrixXd::Zero(m_eq, m_eq);
      VectorXd rhs(n + m_eq);
      rhs << -p.g, p.b_eq;
      const VectorXd sol = kkt.fullPivLu().solve(rhs);
      EXPECT_LE((s.x() - sol.head(n)).norm(), 1e-9 * (1.0 + sol.norm())) << n << " " << m_eq;
      EXPECT_LE((s.equality_multipliers() - sol.tail(m_eq)).norm(), 1e-8 * (1.0 + sol.norm())) << n << " " << m_eq;
      expect_kkt(p, s, 1e-9, "equality only");
    }
  }
}

TEST(QpSolver, BoundsOnlyMatchClamp) {
  Rng rng(3);
  for (int t = 0; t < 100; ++t) {
    const Index n = rng.integer(1, 20);
    QpProblem p;
    p.resize(n, 0, 0);
    p.H = MatrixXd::Zero(n, n);
    for (Index j = 0; j < n; ++j) p.H(j, j) = rng.uniform(0.1, 10.0);
    p.g = 5.0 * rng.gaussian(n);
    for (Index j = 0; j < n; ++j) {
      p.lb(j) = rng.chance(0.2) ? -kInf : rng.uniform(-2.0, 0.0);
      p.ub(j) = rng.chance(0.2) ? kInf : rng.uniform(0.0, 2.0);
    }
    QpSolver s(n, 0, 0);
    ASSERT_EQ(s.solve(p), QpStatus::kOptimal);
    for (Index j = 0; j < n; ++j) {
      const double clamp = std::clamp(-p.g(j) / p.H(j, j), p.lb(j), p.ub(j));
      EXPECT_NEAR(s.x()(j), clamp, 1e-12 * (1.0 + std::abs(clamp)));
    }
    expect_kkt(p, s, 1e-12, "bounds only");
  }
}

// ------------------------------------------------------------------------------------ degenerate

TEST(QpSolver, RedundantAndParallelConstraints) {
  Rng rng(4);
  for (int t = 0; t < 200 / kScale; ++t) {
    const Index n = rng.integer(2, 5);  // with up to 3 rows: at most 8 constraints to enumerate
    const Index m_base = rng.integer(1, 3);
    const QpProblem base = random_problem(rng, {n, 0, m_base}, 1.0, true, 10.0);
    // Each base row again, scaled (with scaled sides), and every bound again as a dense row.
    QpProblem p;
    p.resize(n, 0, 2 * m_base + n);
    p.H = base.H;
    p.g = base.g;
    p.lb = base.lb;
    p.ub = base.ub;
    for (Index i = 0; i < m_base; ++i) {
      const double c = rng.chance(0.5) ? 1.0 : rng.uniform(0.2, 5.0);
      p.A.row(i) = base.A.row(i);
      p.l(i) = base.l(i);
      p.u(i) = base.u(i);
      p.A.row(m_base + i) = c * base.A.row(i);
      p.l(m_base + i) = c * base.l(i);
      p.u(m_base + i) = c * base.u(i);
    }
    for (Index j = 0; j < n; ++j) {
      p.A(2 * m_base + j, j) = 1.0;
      p.l(2 * m_base + j) = base.lb(j);
      p.u(2 * m_base + j) = base.ub(j);
    }
    QpSolver s = solver_for(p);
    QpSolver s_base = solver_for(base);
    ASSERT_EQ(s_base.solve(base), QpStatus::kOptimal);
    ASSERT_EQ(s.solve(p), QpStatus::kOptimal) << t;
    EXPECT_NEAR(s.objective(), s_base.objective(), 1e-9 * std::max(1.0, std::abs(s_base.objective()))) << t;
    expect_kkt(p, s, 1e-9, "redundant rows");
    const double f_ref = brute_force_optimum(base);
    EXPECT_NEAR(s.objective(), f_ref, 1e-9 * std::max(1.0, std::abs(f_ref))) << t;
  }
}

TEST(QpSolver, RedundantEqualities) {
  QpProblem p;
  p.resize(3, 3, 0);
  p.H = MatrixXd::Identity(3, 3);
  p.g << 1.0, -2.0, 0.5;
  p.A_eq << 1.0, 1.0, 0.0,  //
      2.0, 2.0, 0.0,        // twice the first
      0.0, 0.0, 0.0;        // 0 = 0
  p.b_eq << 1.0, 2.0, 0.0;
  QpSolver s(3, 3, 0);
  ASSERT_EQ(s.solve(p), QpStatus::kOptimal);
  expect_kkt(p, s, 1e-12, "redundant equalities");
  EXPECT_NEAR(s.x()(0) + s.x()(1), 1.0, 1e-12);

  p.b_eq(1) = 2.5;  // inconsistent copy
  EXPECT_EQ(s.solve(p), QpStatus::kInfeasible);
  EXPECT_TRUE(s.x().allFinite());
  p.b_eq(1) = 2.0;
  p.b_eq(2) = 1.0;  // 0 = 1
  EXPECT_EQ(s.solve(p), QpStatus::kInfeasible);
  EXPECT_TRUE(s.x().allFinite());
}

TEST(QpSolver, ConstraintsActiveAtUnconstrainedOptimum) {
  Rng rng(5);
  for (int t = 0; t < 100; ++t) {
    const Index n = rng.integer(1, 10);
    const Index m_in = rng.integer(1, 10);
    QpProblem p;
    p.resize(n, 0, m_in);
    p.H = random_spd(rng, n, 2.0);
    p.g = rng.gaussian(n);
    const VectorXd x_u = -p.H.llt().solve(p.g);
    p.A = rng.gaussian(m_in, n);
    const VectorXd v = p.A * x_u;
    for (Index i = 0; i < m_in; ++i) {
      // Rows through the unconstrained minimum, or with their sides just touching it.
      p.l(i) = rng.chance(0.5) ? v(i) : v(i) - 1.0;
      p.u(i) = rng.chance(0.5) ? v(i) : v(i) + 1.0;
    }
    for (Index j = 0; j < n; ++j) {
      if (rng.chance(0.5)) p.lb(j) = x_u(j);
      if (rng.chance(0.5)) p.ub(j) = x_u(j);
    }
    QpSolver s(n, 0, m_in);
    ASSERT_EQ(s.solve(p), QpStatus::kOptimal) << t;
    EXPECT_LE((s.x() - x_u).norm(), 1e-9 * (1.0 + x_u.norm())) << t;
    expect_kkt(p, s, 1e-9, "active at unconstrained optimum");
  }
}

TEST(QpSolver, InfeasibleSetsAreDetected) {
  // Each case: status kInfeasible within the iteration limit and a finite x.
  const auto expect_infeasible = [](const QpProblem& p, const std::string& what) {
    QpSolver s = solver_for(p);
    EXPECT_EQ(s.solve(p), QpStatus::kInfeasible) << what;
    EXPECT_LT(s.iterations(), 10 * (p.g.size() + p.A.rows() + p.A_eq.rows()) + 10) << what;
    EXPECT_TRUE(s.x().allFinite()) << what;
  };
  QpProblem p;
  p.resize(2, 0, 1);
  p.H = MatrixXd::Identity(2, 2);
  p.g << -1.0, -1.0;
  p.A << 1.0, 0.0;
  p.l << 1.0;
  p.ub << 0.0, kInf;
  expect_infeasible(p, "row x0 >= 1 against bound x0 <= 0");

  p.resize(2, 0, 1);
  p.H = MatrixXd::Identity(2, 2);
  p.A << 1.0, 1.0;
  p.l << 3.0;
  p.ub << 1.0, 1.0;
  expect_infeasible(p, "x0 + x1 >= 3, x <= 1");

  p.resize(3, 0, 2);
  p.H = MatrixXd::Identity(3, 3);
  p.A << 1.0, 2.0, -1.0, -2.0, -4.0, 2.0;
  p.l << 1.0, 0.0;
  expect_infeasible(p, "parallel rows a x >= 1, -2 a x >= 0");

  p.resize(2, 1, 0);
  p.H = MatrixXd::Identity(2, 2);
  p.A_eq << 1.0, 0.0;
  p.b_eq << 2.0;
  p.ub << 1.0, kInf;
  expect_infeasible(p, "equality x0 = 2 against bound x0 <= 1");

  p.resize(2, 0, 1);
  p.H = MatrixXd::Identity(2, 2);
  p.A.setZero();
  p.l << 1.0;
  expect_infeasible(p, "zero row with 1 <= 0");

  // Random: a feasible problem plus a row that cuts it off (a x >= max over the box + 1).
  Rng rng(6);
  for (int t = 0; t < 200; ++t) {
    const Index n = rng.integer(1, 10);
    const Index m_in = rng.integer(0, 8);
    QpProblem q = random_problem(rng, {n, 0, m_in + 1}, 2.0, false, 5.0);
    for (Index j = 0; j < n; ++j) {
      q.lb(j) = -1.0;
      q.ub(j) = 1.0;
    }
    q.A.row(m_in).setConstant(1.0);
    q.l(m_in) = static_cast<double>(n) + 0.5;
    q.u(m_in) = kInf;
    expect_infeasible(q, "random cut " + std::to_string(t));
  }
}

TEST(QpSolver, IllConditionedHessian) {
  Rng rng(8);
  double worst_gap = 0.0;
  Kkt worst;
  for (int t = 0; t < 400 / kScale; ++t) {
    const Index n = rng.integer(2, 6);
    const bool bounds = rng.chance(0.5) && n <= 4;  // at most 8 constraints to enumerate
    const Index m_in = rng.integer(1, static_cast<int>(bounds ? 8 - n : 5));
    QpProblem p = random_problem(rng, {n, 0, m_in}, 8.0, bounds, 5.0);
    const bool controller_like = t % 2 == 0;
    // Controller-like: the gradient pulls towards a target (g = -H x_t), as a weighted task does.
    // Otherwise a gradient of the size of H's largest eigenvalue in every direction, which puts
    // the unconstrained minimum ~1e8 away along the soft directions.
    if (controller_like) p.g = -p.H * (3.0 * rng.gaussian(n));
    QpSolver s = solver_for(p);
    ASSERT_EQ(s.solve(p), QpStatus::kOptimal) << t;
    const Kkt r = kkt_residuals(p, s);
    worst.stationarity = std::max(worst.stationarity, r.stationarity);
    worst.primal = std::max(worst.primal, r.primal);
    worst.dual = std::max(worst.dual, r.dual);
    worst.complementarity = std::max(worst.complementarity, r.complementarity);
    EXPECT_LE(r.primal, 1e-9) << t;
    EXPECT_LE(r.dual, 1e-9) << t;
    EXPECT_LE(r.complementarity, 1e-9) << t;
    // A condition number of 1e8 may cost up to 8 digits of the gradient balance.
    EXPECT_LE(r.stationarity, 1e-7) << t;
    {
      const double f_ref = brute_force_optimum(p);
      const double gap = std::abs(s.objective() - f_ref) / std::max(1.0, std::abs(f_ref));
      worst_gap = std::max(worst_gap, gap);
      // With the unconstrained minimum 1e8 away both sides lose digits to the conditioning.
      EXPECT_LE(gap, controller_like ? 1e-9 : 1e-8) << t;
    }
  }
  std::cout << "[ cond 1e8 ] largest relative objective gap " << worst_gap << ", KKT residuals: stationarity "
            << worst.stationarity << ", primal " << worst.primal << ", dual " << worst.dual << ", complementarity "
            << worst.complementarity << "\n";
}

// Found by the random tests: after a step of ~1e11 along a nearly dependent normal, the active
// row 1 drifted by 2e-9 and its parallel copy, row 2, looked violated with no way to enter.
TEST(QpSolver, ParallelEqualityRowsAfterLongSteps) {
  QpProblem p;
  p.resize(3, 0, 4);
  p.H << 1648301937.8725543, -3117171828.3207688, -614270635.10438871,  //
      -3117171828.3207688, 5897082465.2622461, 1161158634.0490916,      //
      -614270635.10438871, 1161158634.0490916, 229047192.35992178;
  p.g << -9566855784.5464382, 23213318880.847328, -1427490321.8666673;
  p.A << 2.3593383488663657, 1.4509423458378123, 0.023909919427844806,  //
      0.29906776081359876, 0.99016352872371283, 2.4916684990632887,     //
      0.30639003669083692, 1.0144063641974219, 2.5526736842933233,      //
      -1.7577429676467424, 0.33699697937164419, 1.5095036671134838;
  p.l << 2.6063273440042232, 5.2039226364559283, 5.3313337525330109, 1.2230310849598096;
  p.u << 2.6063273440042232, 5.2039226364559283, 5.3313337525330109, 3.0514473610116752;
  QpSolver s(3, 0, 4);
  ASSERT_EQ(s.solve(p), QpStatus::kOptimal);
  const Kkt r = kkt_residuals(p, s);
  EXPECT_LE(r.primal, 1e-12);
  EXPECT_LE(r.stationarity, 1e-7);
  const double f_ref = brute_force_optimum(p);
  EXPECT_NEAR(s.objective(), f_ref, 1e-8 * std::abs(f_ref));
}

// ------------------------------------------------------------------------------------ warm start

std::vector<QpActiveSide> random_sides(Rng& rng, Index size) {
  std::vector<QpActiveSide> sides(static_cast<std::size_t>(size));
  for (auto& side : sides) side = static_cast<QpActiveSide>(rng.integer(0, 2));
  return sides;
}

TEST(QpSolver, WarmStartFromWrongActiveSetGivesTheOptimum) {
  Rng rng(9);
  for (int t = 0; t < 2000 / kScale; ++t) {
    const Index n = rng.integer(1, 20);
    const Index m_eq = rng.chance(0.3) ? rng.integer(0, static_cast<int>(std::min<Index>(n, 3))) : 0;
    const Index m_in = rng.integer(0, 30);
    const QpProblem p = random_problem(rng, {n, m_eq, m_in}, rng.uniform(0.0, 4.0), true, 10.0);
    QpSolver cold = solver_for(p);
    ASSERT_EQ(cold.solve(p), QpStatus::kOptimal);

    QpSolver warm = solver_for(p);
    const auto rows = random_sides(rng, m_in);
    const auto bounds = random_sides(rng, n);
    ASSERT_TRUE(warm.set_active_set(rows, bounds));
    ASSERT_EQ(warm.solve(p, {.warm_start = true}), QpStatus::kOptimal) << t;
    const double scale = std::max(1.0, std::abs(cold.objective()));
    EXPECT_NEAR(warm.objective(), cold.objective(), 1e-9 * scale) << t;
    EXPECT_LE((warm.x() - cold.x()).norm(), 1e-6 * (1.0 + cold.x().norm())) << t;
    expect_kkt(p, warm, 1e-9, "warm from wrong set " + std::to_string(t));

    // From its own optimal active set: no iteration at all.
    ASSERT_EQ(warm.solve(p, {.warm_start = true}), QpStatus::kOptimal);
    EXPECT_EQ(warm.iterations(), 0) << t;
    EXPECT_NEAR(warm.objective(), cold.objective(), 1e-9 * scale) << t;
  }
}

TEST(QpSolver, WarmStartAcrossPerturbedProblems) {
  Rng rng(10);
  const QpProblem base = random_problem(rng, {12, 2, 25}, 3.0, true, 10.0);
  QpSolver warm = solver_for(base);
  QpSolver cold = solver_for(base);
  int warm_iterations = 0;
  int cold_iterations = 0;
  for (int t = 0; t < 200; ++t) {
    QpProblem p = base;
    p.g += 0.05 * rng.gaussian(12);
    ASSERT_EQ(warm.solve(p, {.warm_start = true}), QpStatus::kOptimal) << t;
    ASSERT_EQ(cold.solve(p), QpStatus::kOptimal) << t;
    EXPECT_NEAR(warm.objective(), cold.objective(), 1e-9 * std::max(1.0, std::abs(cold.objective())));
    warm_iterations += warm.iterations();
    cold_iterations += cold.iterations();
  }
  EXPECT_LT(warm_iterations, cold_iterations);
}

// Rows with no finite side are neither copied nor scanned: a solver that kept earlier problems'
// rows in their place answers every later problem to the bit as a fresh solver does, cold and from
// the same warm start, on the small-n path and on the blocked one (n >= 16).
TEST(QpSolver, RowsThatBoundNothingAreNeverRead) {
  Rng rng(44);
  for (const Index n : {Index{7}, Index{20}}) {
    const Index m_in = 3 * n;
    QpSolver kept(n, 1, m_in);
    for (int t = 0; t < 60; ++t) {
      QpProblem p = random_problem(rng, {n, 1, m_in}, 2.0, true, 10.0);
      for (Index i = 0; i < m_in; ++i) {
        if (!rng.chance(0.5)) continue;
        p.A.row(i) = 1e3 * rng.gaussian(n).transpose();  // what a stale copy would hold if read
        p.l(i) = rng.chance(0.5) ? -kInf : -1e21;
        p.u(i) = rng.chance(0.5) ? kInf : 1e22;
      }
      const bool warm = t % 2 == 1;
      QpSolver fresh(n, 1, m_in);
      if (warm) {
        ASSERT_TRUE(fresh.set_active_set(kept.active_rows(), kept.active_bounds()));
      }
      const QpStatus status = kept.solve(p, {.warm_start = warm});
      ASSERT_EQ(fresh.solve(p, {.warm_start = warm}), status) << "n " << n << ", problem " << t;
      EXPECT_EQ(kept.iterations(), fresh.iterations()) << "n " << n << ", problem " << t;
      EXPECT_TRUE(kept.x() == fresh.x()) << "n " << n << ", problem " << t;
      EXPECT_TRUE(kept.row_multipliers() == fresh.row_multipliers()) << "n " << n << ", problem " << t;
      if (status == QpStatus::kOptimal) expect_kkt(p, kept, 1e-7, "problem " + std::to_string(t));
    }
  }
}

TEST(QpSolver, WarmStartIgnoresAbsentSidesAndBadSizes) {
  QpProblem p;
  p.resize(2, 0, 1);
  p.H = MatrixXd::Identity(2, 2);
  p.g << 1.0, 1.0;
  p.A << 1.0, 1.0;
  p.u << 5.0;  // lower side absent
  QpSolver s(2, 0, 1);
  const std::vector<QpActiveSide> rows{QpActiveSide::kLower};
  const std::vector<QpActiveSide> bounds{QpActiveSide::kUpper, QpActiveSide::kLower};
  ASSERT_TRUE(s.set_active_set(rows, bounds));
  ASSERT_EQ(s.solve(p, {.warm_start = true}), QpStatus::kOptimal);
  EXPECT_NEAR(s.x()(0), -1.0, 1e-14);
  EXPECT_NEAR(s.x()(1), -1.0, 1e-14);
  EXPECT_FALSE(s.set_active_set(bounds, bounds));
}

// ------------------------------------------------------------------------------------ factor reuse

TEST(QpSolver, HessianFactorReuseAndCallerFactor) {
  Rng rng(11);
  const QpProblem p = random_problem(rng, {9, 1, 15}, 3.0, true, 10.0);
  QpSolver reference = solver_for(p);
  ASSERT_EQ(reference.solve(p), QpStatus::kOptimal);

  QpSolver s = solver_for(p);
  EXPECT_EQ(s.solve(p, {.reuse_hessian_factor = true}), QpStatus::kInvalidInput);
  EXPECT_EQ(s.invalid_reason(), QpInvalidReason::kMissingHessianFactor);

  // Stored by a solve, then reused with problem.H not even present.
  ASSERT_EQ(s.solve(p), QpStatus::kOptimal);
  QpProblem without_h = p;
  without_h.H.resize(0, 0);
  ASSERT_EQ(s.solve(without_h, {.reuse_hessian_factor = true}), QpStatus::kOptimal);
  EXPECT_LE((s.x() - reference.x()).norm(), 1e-12 * (1.0 + reference.x().norm()));

  // From set_hessian.
  QpSolver s2 = solver_for(p);
  ASSERT_EQ(s2.set_hessian(p.H), QpInvalidReason::kNone);
  ASSERT_EQ(s2.solve(without_h, {.reuse_hessian_factor = true}), QpStatus::kOptimal);
  EXPECT_LE((s2.x() - reference.x()).norm(), 1e-12 * (1.0 + reference.x().norm()));

  // The caller's own factor.
  QpSolver s3 = solver_for(p);
  const MatrixXd l = p.H.llt().matrixL();
  ASSERT_EQ(s3.set_hessian_factor(l), QpInvalidReason::kNone);
  ASSERT_EQ(s3.solve(without_h, {.warm_start = true, .reuse_hessian_factor = true}), QpStatus::kOptimal);
  EXPECT_LE((s3.x() - reference.x()).norm(), 1e-10 * (1.0 + reference.x().norm()));
  EXPECT_NEAR(s3.objective(), reference.objective(), 1e-10 * std::max(1.0, std::abs(reference.objective())));

  MatrixXd bad = l;
  bad(2, 2) = 0.0;
  EXPECT_EQ(s3.set_hessian_factor(bad), QpInvalidReason::kInvalidHessianFactor);
  EXPECT_EQ(s3.solve(without_h, {.reuse_hessian_factor = true}), QpStatus::kInvalidInput);
  EXPECT_EQ(s3.invalid_reason(), QpInvalidReason::kMissingHessianFactor);
  EXPECT_EQ(s3.set_hessian(MatrixXd::Identity(3, 3)), QpInvalidReason::kDimensionMismatch);
}

// J = L^-T is formed only when a constraint enters. Alternating, on one solver, problems whose
// optimum is unconstrained (no J formed) with problems that need constraints (J formed then), with
// new Hessians and with the factor the unconstrained solve before stored (reused: J formed from
// it later), n = 7 (the unrolled factor) and n = 12: each answer is a fresh solver's to rounding
// and meets KKT, i.e. never a J left from another Hessian.
TEST(QpSolver, TheInverseFactorIsFormedFromTheCurrentHessianWhenFirstNeeded) {
  Rng rng(4401);
  for (const Index n : {Index{7}, Index{12}}) {
    QpSolver s(n, 0, 6);
    MatrixXd previous_h;
    int constrained = 0;
    for (int round = 0; round < 40; ++round) {
      QpProblem p = random_problem(rng, {n, 0, 6}, 2.0, true, 10.0);
      const bool free = round % 2 == 0;
      const bool reuse = round % 4 == 1;  // the factor the free solve of the round before stored
      if (free) {  // every side absent: the unconstrained minimum is the answer
        p.l.setConstant(-kInf);
        p.u.setConstant(kInf);
        p.lb.setConstant(-kInf);
        p.ub.setConstant(kInf);
      }
      if (reuse) p.H = previous_h;
      QpSolver fresh = solver_for(p);
      ASSERT_EQ(fresh.solve(p), QpStatus::kOptimal) << n << " round " << round;
      QpProblem input = p;
      if (reuse) input.H.resize(0, 0);
      ASSERT_EQ(s.solve(input, {.warm_start = round % 3 == 0, .reuse_hessian_factor = reuse}), QpStatus::kOptimal)
          << n << " round " << round;
      EXPECT_LE((s.x() - fresh.x()).norm(), 1e-9 * (1.0 + fresh.x().norm())) << n << " round " << round;
      expect_kkt(p, s, 1e-7, "round " + std::to_string(round));
      if (free) {
        EXPECT_EQ(s.active_count(), 0);
      }
      constrained += s.active_count() > 0 ? 1 : 0;
      previous_h = p.H;
    }
    EXPECT_GE(constrained, 10) << n;  // the constrained rounds did need constraints
  }
}

// ------------------------------------------------------------------------------------ bad input

TEST(QpSolver, InvalidInputIsReported) {
  Rng rng(12);
  const QpProblem good = random_problem(rng, {5, 1, 6}, 2.0, true, 5.0);
  QpSolver s = solver_for(good);
  ASSERT_EQ(s.solve(good), QpStatus::kOptimal);
  const std::vector<QpActiveSide> rows_before(s.active_rows().begin(), s.active_rows().end());

  const auto expect_invalid = [&](const QpProblem& p, QpInvalidReason reason, Index index, const std::string& what) {
    EXPECT_EQ(s.solve(p), QpStatus::kInvalidInput) << what;
    EXPECT_EQ(s.status(), QpStatus::kInvalidInput) << what;
    EXPECT_EQ(s.invalid_reason(), reason) << what << ": " << to_string(s.invalid_reason());
    EXPECT_EQ(s.invalid_index(), index) << what;
    EXPECT_EQ(s.iterations(), 0) << what;
    EXPECT_TRUE(s.x().allFinite()) << what;
    EXPECT_TRUE(s.x().isZero()) << what;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  QpProblem p = good;
  p.g(3) = nan;
  expect_invalid(p, QpInvalidReason::kNonFiniteGradient, 3, "NaN in g");
  EXPECT_TRUE(std::equal(rows_before.begin(), rows_before.end(), s.active_rows().begin()));

  p = good;
  p.H(1, 2) = kInf;
  expect_invalid(p, QpInvalidReason::kNonFiniteHessian, 1, "Inf in H");
  p = good;
  p.H(0, 4) = nan;  // the upper triangle is not used, but NaN anywhere is invalid
  expect_invalid(p, QpInvalidReason::kNonFiniteHessian, 0, "NaN in upper H");
  p = good;
  p.H(2, 2) = -1.0;
  expect_invalid(p, QpInvalidReason::kHessianNotPositiveDefinite, 2, "indefinite H");
  p = good;
  p.H.setZero();
  expect_invalid(p, QpInvalidReason::kHessianNotPositiveDefinite, 0, "zero H");
  p = good;
  p.H = MatrixXd::Ones(5, 5);
  expect_invalid(p, QpInvalidReason::kHessianNotPositiveDefinite, 1, "rank-one H");
  p = good;
  p.A_eq(0, 1) = nan;
  expect_invalid(p, QpInvalidReason::kNonFiniteEqualityRows, 0, "NaN in A_eq");
  p = good;
  p.b_eq(0) = kInf;
  expect_invalid(p, QpInvalidReason::kNonFiniteEqualityTarget, 0, "Inf in b_eq");
  p = good;
  p.A(4, 4) = -kInf;
  expect_invalid(p, QpInvalidReason::kNonFiniteInequalityRows, 4, "Inf in A");
  // A row that bounds nothing (both sides absent) is neither copied nor scaled, but still checked:
  // a NaN or Inf in it, alone in an all-zero row or among finite entries, at its own index.
  for (const double bad : {nan, kInf}) {
    for (const bool zero_row : {true, false}) {
      p = good;
      p.l(3) = -kInf;
      p.u(3) = kInf;
      if (zero_row) p.A.row(3).setZero();
      p.A(3, 2) = bad;
      expect_invalid(p, QpInvalidReason::kNonFiniteInequalityRows, 3, "non-finite entry in a row that bounds nothing");
    }
  }
  p = good;  // finite entries whose squares overflow, in a row that bounds nothing: valid
  p.l(3) = -kInf;
  p.u(3) = kInf;
  p.A.row(3).setConstant(1e200);
  EXPECT_EQ(s.solve(p), QpStatus::kOptimal);
  p = good;
  p.l(2) = p.u(2) + 1.0;
  expect_invalid(p, QpInvalidReason::kRowBoundsInverted, 2, "l > u");
  p = good;
  p.u(1) = nan;
  expect_invalid(p, QpInvalidReason::kInvalidRowBound, 1, "NaN in u");
  p = good;
  p.l(5) = kInf;
  expect_invalid(p, QpInvalidReason::kInvalidRowBound, 5, "l = +inf");
  p = good;
  p.lb(3) = 2.0;
  p.ub(3) = 1.0;
  expect_invalid(p, QpInvalidReason::kVariableBoundsInverted, 3, "lb > ub");
  p = good;
  p.ub(0) = -kInf;
  expect_invalid(p, QpInvalidReason::kInvalidVariableBound, 0, "ub = -inf");
  p = good;
  p.g.resize(4);
  p.g.setZero();
  expect_invalid(p, QpInvalidReason::kDimensionMismatch, -1, "short g");

  QpSolver empty;
  EXPECT_EQ(empty.solve(good), QpStatus::kInvalidInput);
  EXPECT_EQ(empty.invalid_reason(), QpInvalidReason::kDimensionMismatch);

  // Still usable afterwards, warm start included.
  ASSERT_EQ(s.solve(good, {.warm_start = true}), QpStatus::kOptimal);
  EXPECT_EQ(s.iterations(), 0);
}

TEST(QpSolver, EmptySidesMeanAbsent) {
  QpProblem p;
  p.resize(2, 0, 1);
  p.H = MatrixXd::Identity(2, 2);
  p.g << -3.0, 0.0;
  p.A << 1.0, 0.0;
  p.u << 1.0;
  p.l.resize(0);
  p.lb.resize(0);
  p.ub.resize(0);
  QpSolver s(2, 0, 1);
  ASSERT_EQ(s.solve(p), QpStatus::kOptimal);
  EXPECT_NEAR(s.x()(0), 1.0, 1e-14);
  EXPECT_EQ(s.active_rows()[0], QpActiveSide::kUpper);
  EXPECT_NEAR(s.row_multipliers()(0), 2.0, 1e-14);  // H x + g + y a = 0: 1 - 3 + y = 0
}

TEST(QpSolver, IterationLimitKeepsAFiniteIterate) {
  Rng rng(13);
  const QpProblem p = random_problem(rng, {10, 0, 30}, 2.0, true, 30.0);
  QpSolver s = solver_for(p);
  ASSERT_EQ(s.solve(p), QpStatus::kOptimal);
  ASSERT_GT(s.iterations(), 2);
  s.settings().max_iterations = 2;
  EXPECT_EQ(s.solve(p), QpStatus::kIterationLimit);
  EXPECT_EQ(s.iterations(), 2);
  EXPECT_TRUE(s.x().allFinite());
}

// ------------------------------------------------------------------------------------ allocation

// tests/support counts malloc as well as operator new (glibc, no ASan).
std::size_t malloc_calls() { return test::thread_allocation_count(); }

// The interposed malloc must see Eigen's heap use, or the zero counts below would prove nothing.
TEST(QpSolver, MallocCounterSeesEigenAllocations) {
  if (!test::counts_malloc()) GTEST_SKIP() << "malloc is not interposed under AddressSanitizer";
  const std::size_t before = malloc_calls();
  VectorXd v = VectorXd::Ones(100);
  EXPECT_GT(malloc_calls(), before);
  EXPECT_EQ(v.sum(), 100.0);
}

TEST(QpSolver, SolveNeverAllocatesAfterResize) {
  Rng rng(14);
  // n = 7 runs the small kernels, n = 20 Eigen's products.
  for (const Shape shape : {Shape{7, 0, 17}, Shape{7, 2, 10}, Shape{20, 2, 40}}) {
    const QpProblem p = random_problem(rng, shape, 3.0, true, 10.0);
    QpProblem infeasible = p;
    infeasible.A.row(0).setZero();
    infeasible.A(0, 0) = 1.0;
    infeasible.l(0) = infeasible.ub(0) + 1.0;
    infeasible.u(0) = kInf;
    QpProblem invalid = p;
    invalid.g(0) = std::numeric_limits<double>::quiet_NaN();
    QpProblem not_definite = p;
    not_definite.H(3, 3) = -1.0;
    const MatrixXd factor = p.H.llt().matrixL();
    const std::vector<QpActiveSide> rows(static_cast<std::size_t>(shape.m_in), QpActiveSide::kLower);
    const std::vector<QpActiveSide> bounds(static_cast<std::size_t>(shape.n), QpActiveSide::kUpper);

    QpSolver s;
    s.resize(shape.n, shape.m_eq, shape.m_in);
    QpStatus statuses[9];
    std::size_t allocations = 0;
    std::size_t mallocs = 0;
    {
      const std::size_t malloc_start = malloc_calls();
      test::AllocationCounter count;
      test::NoMallocScope no_malloc;
      statuses[0] = s.solve(p);
      statuses[1] = s.solve(p, {.warm_start = true});
      statuses[2] = s.solve(p, {.warm_start = true, .reuse_hessian_factor = true});
      statuses[3] = s.solve(infeasible, {.warm_start = true});
      statuses[4] = s.solve(invalid);
      statuses[5] = s.solve(not_definite);
      s.set_active_set(rows, bounds);
      statuses[6] = s.solve(p, {.warm_start = true});
      s.set_hessian(p.H);
      statuses[7] = s.solve(p, {.reuse_hessian_factor = true});
      s.set_hessian_factor(factor);
      statuses[8] = s.solve(p, {.warm_start = true, .reuse_hessian_factor = true});
      allocations = count.allocations();
      mallocs = malloc_calls() - malloc_start;
    }
    EXPECT_EQ(allocations, 0u) << shape.n;
    EXPECT_EQ(mallocs, 0u) << shape.n;
    EXPECT_EQ(statuses[0], QpStatus::kOptimal);
    EXPECT_EQ(statuses[1], QpStatus::kOptimal);
    EXPECT_EQ(statuses[2], QpStatus::kOptimal);
    EXPECT_EQ(statuses[3], QpStatus::kInfeasible);
    EXPECT_EQ(statuses[4], QpStatus::kInvalidInput);
    EXPECT_EQ(statuses[5], QpStatus::kInvalidInput);
    EXPECT_EQ(statuses[6], QpStatus::kOptimal);
    EXPECT_EQ(statuses[7], QpStatus::kOptimal);
    EXPECT_EQ(statuses[8], QpStatus::kOptimal);
  }
}

TEST(QpSolver, LargestSizeSolves) {
  Rng rng(15);
  const QpProblem p = random_problem(rng, {60, 5, 300}, 3.0, true, 10.0);
  QpSolver s = solver_for(p);
  std::size_t allocations = 0;
  std::size_t mallocs = 0;
  QpStatus status{};
  {
    const std::size_t malloc_start = malloc_calls();
    test::AllocationCounter count;
    status = s.solve(p);
    allocations = count.allocations();
    mallocs = malloc_calls() - malloc_start;
  }
  ASSERT_EQ(status, QpStatus::kOptimal);
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(mallocs, 0u);
  expect_kkt(p, s, 1e-9, "n 60 m 300");
  ASSERT_EQ(s.solve(p, {.warm_start = true}), QpStatus::kOptimal);
  EXPECT_EQ(s.iterations(), 0);
}

}  // namespace
}  // namespace phri
