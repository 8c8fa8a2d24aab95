// The Ceres backend of naocalib: interprets the chains shipped by Rust (src/solve/ceres.rs)
// on Jets and runs Levenberg–Marquardt. See ceres_shim.h.
//
// The arithmetic below mirrors src/model/{pose,chain,camera}.rs operation by operation, so
// that Rust and Ceres agree on residuals to rounding and on derivatives exactly.

#include "naocalib/cpp/ceres_shim.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <ceres/crs_matrix.h>
#include <ceres/cost_function.h>
#include <ceres/jet.h>
#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <ceres/types.h>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <glog/logging.h>

#include "naocalib/src/solve/ceres/bridge.rs.h"

namespace naocalib {
namespace {

// Most parameters one amount depends on (chain::MAX_TERMS in Rust).
constexpr int kTerms = 3;

[[noreturn]] void fail(const std::string& message) { throw std::invalid_argument(message); }

// ---------------------------------------------------------------------------------------
// Logging: glog is initialised once, to stderr, and kept silent unless asked to be verbose.

void init_logging(bool verbose) {
  static std::once_flag once;
  static std::mutex mutex;
  std::call_once(once, [] {
    FLAGS_logtostderr = true;
    FLAGS_minloglevel = google::GLOG_FATAL;
    if (!google::IsGoogleLoggingInitialized()) google::InitGoogleLogging("naocalib");
  });
  std::lock_guard<std::mutex> lock(mutex);
  FLAGS_minloglevel = verbose ? google::GLOG_INFO : google::GLOG_FATAL;
  // Ceres prints its per-iteration progress through VLOG(1) unless sent to stdout.
  FLAGS_v = verbose ? 1 : 0;
}

// ---------------------------------------------------------------------------------------
// Validation: everything that could index out of range or trip a Ceres CHECK.

bool finite(double x) { return std::isfinite(x); }

std::size_t vertex_total(const FfiProblem& p) { return p.points.size() / 3; }

void validate(const FfiAmount& a, std::size_t n, const std::string& where) {
  if (!finite(a.constant)) fail(where + "constant is not finite");
  for (int k = 0; k < kTerms; ++k) {
    if (a.params[k] < -1 || a.params[k] >= static_cast<std::int64_t>(n))
      fail(where + "parameter index " + std::to_string(a.params[k]) + " out of range (" +
           std::to_string(n) + " free parameters)");
    if (!finite(a.scales[k])) fail(where + "scale is not finite");
  }
}

void validate(const FfiProblem& p) {
  const std::size_t n = p.params.size();
  if (n == 0) fail("no free parameters");
  if (n > static_cast<std::size_t>(INT_MAX)) fail("too many free parameters");
  if (p.param_block.size() != n)
    fail("param_block has " + std::to_string(p.param_block.size()) + " entries for " +
         std::to_string(n) + " free parameters");
  for (std::size_t i = 0; i < n; ++i)
    if (!finite(p.params[i])) fail("start value of free parameter " + std::to_string(i) +
                                   " is not finite");
  if (p.points.size() % 3 != 0) fail("points must hold 3 numbers per vertex");
  if (p.pixels.size() != 2 * vertex_total(p))
    fail("pixels must hold 2 numbers per vertex (" + std::to_string(vertex_total(p)) +
         " vertices, " + std::to_string(p.pixels.size()) + " numbers)");
  for (double x : p.points)
    if (!finite(x)) fail("a vertex position is not finite");
  for (double x : p.pixels)
    if (!finite(x)) fail("an observed pixel is not finite");
  for (double x : p.weights)
    if (!finite(x)) fail("a whitening weight is not finite");
  for (const FfiProjection& c : p.projections) {
    for (const FfiAmount* a : {&c.fx, &c.fy, &c.cx, &c.cy, &c.k1, &c.k2})
      validate(*a, n, "projection: ");
    for (double x : {c.p1, c.p2, c.k3})
      if (!finite(x)) fail("a distortion coefficient is not finite");
  }

  for (std::size_t s = 0; s < p.steps.size(); ++s) {
    const FfiStep& step = p.steps[s];
    const std::string where = "step " + std::to_string(s) + ": ";
    if (step.kind == StepKind::Fixed) {
      for (double x : step.rotation)
        if (!finite(x)) fail(where + "rotation is not finite");
      for (double x : step.translation)
        if (!finite(x)) fail(where + "translation is not finite");
    } else if (step.kind == StepKind::Rotate || step.kind == StepKind::Translate) {
      if (step.axis != StepAxis::X && step.axis != StepAxis::Y && step.axis != StepAxis::Z)
        fail(where + "unknown axis");
      validate(step.amount, n, where);
    } else {
      fail(where + "unknown kind");
    }
  }

  bool any_residual = false;
  for (std::size_t c = 0; c < p.captures.size(); ++c) {
    const FfiCapture& cap = p.captures[c];
    const std::string where = "capture " + std::to_string(c) + ": ";
    const std::uint64_t end_step = std::uint64_t{cap.first_step} + cap.camera_steps +
                                   cap.board_steps;
    if (end_step > p.steps.size()) fail(where + "steps out of range");
    if (cap.projection >= p.projections.size()) fail(where + "projection out of range");
    if (std::uint64_t{cap.first_vertex} + cap.vertex_count > vertex_total(p))
      fail(where + "vertices out of range");
    if (cap.vertex_count > 1u << 20) fail(where + "too many vertices");
    any_residual = any_residual || cap.vertex_count > 0;
    if (cap.first_weight < -1) fail(where + "first_weight must be -1 or an index");
    if (cap.first_weight >= 0) {
      const std::uint64_t m = 2 * std::uint64_t{cap.vertex_count};
      if (cap.whitening_rank < -1 || cap.whitening_rank > static_cast<std::int64_t>(m))
        fail(where + "whitening rank out of range");
      const std::uint64_t q = cap.whitening_rank < 0 ? 0 : cap.whitening_rank;
      const std::uint64_t size = cap.whitening_rank < 0 ? m * m : 1 + m * q + q;
      if (static_cast<std::uint64_t>(cap.first_weight) + size > p.weights.size())
        fail(where + "whitening out of range of weights");
    }
  }
  if (!any_residual) fail("no observed vertices");
}

void validate(const FfiProblem& p, const FfiOptions& o) {
  if (o.loss != LossKind::Squared && o.loss != LossKind::Huber && o.loss != LossKind::Cauchy)
    fail("unknown loss");
  if (o.loss != LossKind::Squared) {
    if (!(finite(o.loss_scale) && o.loss_scale > 0.0))
      fail("robust loss scale must be a positive number, got " + std::to_string(o.loss_scale));
    for (const FfiCapture& cap : p.captures)
      if (cap.first_weight >= 0)
        fail("a whitening matrix cannot be combined with a robust loss");
  }
  const double tolerances[] = {o.function_tolerance, o.gradient_tolerance,
                               o.parameter_tolerance};
  for (double t : tolerances)
    if (!(finite(t) && t >= 0.0)) fail("tolerances must be finite and non-negative");
  if (o.linear_solver != LinearSolver::DenseQr &&
      o.linear_solver != LinearSolver::DenseNormalCholesky)
    fail("unknown linear solver");
}

// ---------------------------------------------------------------------------------------
// Parameter blocks: free parameters grouped by `param_block` id, in order of first
// appearance; within a block in order of their index.

struct Layout {
  std::vector<std::vector<int>> members;  // per block: global free-parameter indices
  std::vector<int> block_of;              // per free parameter
  std::vector<int> offset_of;             // per free parameter: position in its block
};

Layout make_layout(const FfiProblem& p) {
  Layout layout;
  const int n = static_cast<int>(p.params.size());
  std::vector<std::uint32_t> ids;
  layout.block_of.resize(n);
  layout.offset_of.resize(n);
  for (int g = 0; g < n; ++g) {
    const auto it = std::find(ids.begin(), ids.end(), p.param_block[g]);
    const int b = static_cast<int>(it - ids.begin());
    if (it == ids.end()) {
      ids.push_back(p.param_block[g]);
      layout.members.emplace_back();
    }
    layout.block_of[g] = b;
    layout.offset_of[g] = static_cast<int>(layout.members[b].size());
    layout.members[b].push_back(g);
  }
  return layout;
}

// ---------------------------------------------------------------------------------------
// The model on any scalar (double or Jet).

inline double value_of(double x) { return x; }
template <typename T, int N>
double value_of(const ceres::Jet<T, N>& x) {
  return x.a;
}

template <typename T>
struct Frame {
  T R[3][3];
  T t[3];
};

template <typename T>
void set_fixed(Frame<T>& f, const FfiStep& s) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) f.R[i][j] = T(s.rotation[3 * i + j]);
    f.t[i] = T(s.translation[i]);
  }
}

// f ← f · F for a constant F (Pose::then_fixed).
template <typename T>
void then_fixed(Frame<T>& f, const FfiStep& s) {
  const double* F = s.rotation.data();
  const double* ft = s.translation.data();
  for (int i = 0; i < 3; ++i) {
    const T r0 = f.R[i][0], r1 = f.R[i][1], r2 = f.R[i][2];
    for (int j = 0; j < 3; ++j) f.R[i][j] = r0 * F[j] + r1 * F[3 + j] + r2 * F[6 + j];
    f.t[i] = r0 * ft[0] + r1 * ft[1] + r2 * ft[2] + f.t[i];
  }
}

// f ← f · Rot_axis(angle) (Pose::rotate).
template <typename T>
void rotate(Frame<T>& f, int axis, const T& angle) {
  using std::cos;
  using std::sin;
  const T s = sin(angle), c = cos(angle);
  static constexpr int kA[3] = {1, 2, 0};
  static constexpr int kB[3] = {2, 0, 1};
  const int a = kA[axis], b = kB[axis];
  for (int row = 0; row < 3; ++row) {
    const T ra = f.R[row][a], rb = f.R[row][b];
    f.R[row][a] = ra * c + rb * s;
    f.R[row][b] = rb * c - ra * s;
  }
}

// f ← f · Trans_axis(distance) (Pose::translate).
template <typename T>
void translate(Frame<T>& f, int axis, const T& distance) {
  for (int i = 0; i < 3; ++i) f.t[i] += f.R[i][axis] * distance;
}

// One residual block: the vertices [first, first + count) of one capture, as a function
// of its free *amounts* — the angles and lengths of its chain steps and the intrinsics that
// depend on free parameters, one direction each. A leg joint's angle depends on three
// parameters (offset, compliance, play) but is one amount, so the Jets are as wide as the
// capture's free amounts, not its free parameters; CaptureCost applies the chain rule
// through the affine amounts (∂r/∂α = Σ scale · ∂r/∂amount) in double.
class CaptureFunctor {
 public:
  CaptureFunctor(const FfiProblem& problem, const FfiCapture& capture, std::uint32_t first,
                 std::uint32_t count)
      : problem_(problem), capture_(capture), first_(first), count_(count) {
    const std::uint32_t steps = capture.camera_steps + capture.board_steps;
    step_direction_.assign(steps, -1);
    for (std::uint32_t k = 0; k < steps; ++k) {
      const FfiStep& s = problem.steps[capture.first_step + k];
      if (s.kind != StepKind::Fixed && s.amount.params[0] >= 0) {
        step_direction_[k] = static_cast<int>(amounts_.size());
        amounts_.push_back(&s.amount);
      }
    }
    const FfiProjection& c = problem.projections[capture.projection];
    const FfiAmount* intrinsics[6] = {&c.fx, &c.fy, &c.cx, &c.cy, &c.k1, &c.k2};
    for (int i = 0; i < 6; ++i) {
      projection_direction_[i] = -1;
      if (intrinsics[i]->params[0] >= 0) {
        projection_direction_[i] = static_cast<int>(amounts_.size());
        amounts_.push_back(intrinsics[i]);
        projection_free_ = true;
      }
    }
  }

  // The free amounts, one per direction.
  const std::vector<const FfiAmount*>& amounts() const { return amounts_; }
  int residual_count() const { return static_cast<int>(2 * count_); }

  // The residuals at the given free amounts (`amounts[d]` for direction d).
  template <typename T>
  bool operator()(const T* amounts, T* residuals) const {
    Frame<T> camera, board;
    const FfiStep* steps = problem_.steps.data() + capture_.first_step;
    chain(steps, 0, capture_.camera_steps, amounts, camera);
    chain(steps + capture_.camera_steps, capture_.camera_steps, capture_.board_steps, amounts,
          board);

    // T_CB = T_OC⁻¹ · T_OB (Pose::inverse_then).
    Frame<T> cb;
    const T d[3] = {board.t[0] - camera.t[0], board.t[1] - camera.t[1],
                    board.t[2] - camera.t[2]};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        cb.R[i][j] = camera.R[0][i] * board.R[0][j] + camera.R[1][i] * board.R[1][j] +
                     camera.R[2][i] * board.R[2][j];
      cb.t[i] = camera.R[0][i] * d[0] + camera.R[1][i] * d[1] + camera.R[2][i] * d[2];
    }

    const std::size_t v0 = std::size_t{capture_.first_vertex} + first_;
    const double* points = problem_.points.data() + 3 * v0;
    const double* pixels = problem_.pixels.data() + 2 * v0;
    T* out = residuals;
    for (std::uint32_t k = 0; k < count_; ++k) {
      const double* pb = points + 3 * k;
      T pc[3];
      for (int i = 0; i < 3; ++i)
        pc[i] = cb.R[i][0] * pb[0] + cb.R[i][1] * pb[1] + cb.R[i][2] * pb[2] + cb.t[i];
      T uv[2];
      if (!project(pc, uv, amounts)) return false;
      out[2 * k] = uv[0] - pixels[2 * k];
      out[2 * k + 1] = uv[1] - pixels[2 * k + 1];
    }
    return true;
  }

 private:
  // Chain::eval over steps [first, first + count) of the capture.
  template <typename T>
  void chain(const FfiStep* steps, std::uint32_t first, std::uint32_t count, const T* amounts,
             Frame<T>& f) const {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) f.R[i][j] = T(i == j ? 1.0 : 0.0);
      f.t[i] = T(0.0);
    }
    for (std::uint32_t k = 0; k < count; ++k) {
      const FfiStep& s = steps[k];
      const int axis = static_cast<int>(s.axis);
      if (s.kind == StepKind::Fixed) {
        if (k == 0)
          set_fixed(f, s);
        else
          then_fixed(f, s);
        continue;
      }
      const int direction = step_direction_[first + k];
      const T amount = direction >= 0 ? amounts[direction] : T(s.amount.constant);
      if (s.kind == StepKind::Rotate)
        rotate(f, axis, amount);
      else
        translate(f, axis, amount);
    }
  }

  // Intrinsic i (fx, fy, cx, cy, k1, k2) at the given amounts.
  template <typename T>
  T intrinsic(int i, const FfiAmount& a, const T* amounts) const {
    return projection_direction_[i] >= 0 ? amounts[projection_direction_[i]] : T(a.constant);
  }

  // Projection::project_with: pinhole with optional OpenCV distortion (camera::distort);
  // false behind the camera.
  template <typename T>
  bool project(const T (&p)[3], T (&uv)[2], const T* amounts) const {
    if (value_of(p[0]) <= 0.0) return false;
    const FfiProjection& c = problem_.projections[capture_.projection];
    const T inv = T(1.0) / p[0];
    T a = -(p[1] * inv);
    T b = -(p[2] * inv);
    if (!projection_free_) {
      // Constant intrinsics (the usual case): double coefficients, cheaper on Jets.
      if (c.distorted) {
        const double k1 = c.k1.constant, k2 = c.k2.constant;
        const T r2 = a * a + b * b;
        const T radial = T(1.0) + r2 * (k1 + r2 * (k2 + r2 * c.k3));
        const T ab = a * b;
        const T da = ab * c.p1 * 2.0 + (r2 + a * a * 2.0) * c.p2;
        const T db = (r2 + b * b * 2.0) * c.p1 + ab * c.p2 * 2.0;
        a = a * radial + da;
        b = b * radial + db;
      }
      uv[0] = a * c.fx.constant + c.cx.constant;
      uv[1] = b * c.fy.constant + c.cy.constant;
      return true;
    }
    if (c.distorted) {
      const T k1 = intrinsic(4, c.k1, amounts), k2 = intrinsic(5, c.k2, amounts);
      const T p1 = T(c.p1), p2 = T(c.p2), k3 = T(c.k3);
      const T r2 = a * a + b * b;
      const T radial = T(1.0) + r2 * (k1 + r2 * (k2 + r2 * k3));
      const T ab = a * b;
      const T da = ab * p1 * 2.0 + (r2 + a * a * 2.0) * p2;
      const T db = (r2 + b * b * 2.0) * p1 + ab * p2 * 2.0;
      a = a * radial + da;
      b = b * radial + db;
    }
    uv[0] = a * intrinsic(0, c.fx, amounts) + intrinsic(2, c.cx, amounts);
    uv[1] = b * intrinsic(1, c.fy, amounts) + intrinsic(3, c.cy, amounts);
    return true;
  }

  const FfiProblem& problem_;
  const FfiCapture& capture_;
  std::uint32_t first_, count_;
  std::vector<int> step_direction_;  // per chain step: its direction, or −1 if constant
  int projection_direction_[6];      // per intrinsic: its direction, or −1 if constant
  std::vector<const FfiAmount*> amounts_;
  bool projection_free_ = false;  // whether an intrinsic depends on a free parameter
};

// Jet widths of the autodiff passes. A capture of the paper's model has at most camera (3,
// its own camera's: lower or upper) + leg (6) + board (3) = 12 free amounts; one of the extended model with every family
// free 27. Each block gets the narrower width that covers its amounts in one pass (a pass
// re-evaluates the whole chain), several passes of the wider one beyond.
constexpr int kNarrow = 12;
constexpr int kWide = 28;

// The autodiff cost of one residual block over its parameter blocks: Jets over the free
// amounts, then the chain rule through `constant + Σ scale · α` in double.
class CaptureCost : public ceres::CostFunction {
 public:
  // `slot`/`offset`: per free parameter, its block's position in this block list and its
  // position in the block (−1 where not referenced).
  CaptureCost(std::unique_ptr<CaptureFunctor> functor, const std::vector<int>& sizes,
              const std::vector<int>& slot, const std::vector<int>& offset)
      : functor_(std::move(functor)) {
    *mutable_parameter_block_sizes() = sizes;
    set_num_residuals(functor_->residual_count());
    for (const FfiAmount* a : functor_->amounts()) {
      std::vector<Term> terms;
      for (int k = 0; k < kTerms; ++k)
        if (a->params[k] >= 0)
          terms.push_back({a->params[k], slot[a->params[k]], offset[a->params[k]], a->scales[k]});
      terms_.push_back(std::move(terms));
    }
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    // `constant + Σ scale · α` (Affine::eval, same order of operations).
    const std::size_t directions = terms_.size();
    std::vector<double> values(directions);
    for (std::size_t d = 0; d < directions; ++d) {
      const std::vector<Term>& t = terms_[d];
      double value = parameters[t[0].slot][t[0].offset] * t[0].scale +
                     functor_->amounts()[d]->constant;
      for (std::size_t k = 1; k < t.size(); ++k)
        value += parameters[t[k].slot][t[k].offset] * t[k].scale;
      values[d] = value;
    }
    if (jacobians == nullptr) return (*functor_)(values.data(), residuals);

    // ∂r/∂amount, row major (m × directions).
    const int m = num_residuals();
    // Every entry is written by the passes below (each covers its directions for every
    // residual), so the buffer is left uninitialised.
    std::unique_ptr<double[]> buffer(new double[static_cast<std::size_t>(m) * directions]);
    double* gradient = buffer.get();
    if (directions <= static_cast<std::size_t>(kNarrow)) {
      if (!pass<kNarrow>(values, 0, residuals, gradient)) return false;
    } else {
      for (std::size_t first = 0; first < directions; first += kWide)
        if (!pass<kWide>(values, first, residuals, gradient)) return false;
    }
    if (directions == 0 && !(*functor_)(values.data(), residuals)) return false;

    const std::vector<std::int32_t>& sizes = parameter_block_sizes();
    for (std::size_t b = 0; b < sizes.size(); ++b)
      if (jacobians[b] != nullptr)
        std::fill(jacobians[b], jacobians[b] + static_cast<std::size_t>(m) * sizes[b], 0.0);
    for (std::size_t d = 0; d < directions; ++d)
      for (const Term& t : terms_[d]) {
        double* jac = jacobians[t.slot];
        if (jac == nullptr) continue;
        const int size = sizes[t.slot];
        for (int r = 0; r < m; ++r)
          jac[r * size + t.offset] += gradient[r * directions + d] * t.scale;
      }
    return true;
  }

 private:
  struct Term {
    int param, slot, offset;
    double scale;
  };

  // One Jet pass over directions [first, first + N): residuals and their columns of ∂r/∂amount.
  template <int N>
  bool pass(const std::vector<double>& values, std::size_t first, double* residuals,
            double* gradient) const {
    using J = ceres::Jet<double, N>;
    const std::size_t directions = values.size();
    std::vector<J> amounts(directions);
    for (std::size_t d = 0; d < directions; ++d) {
      amounts[d] = J(values[d]);
      if (d >= first && d < first + N) amounts[d].v[d - first] = 1.0;
    }
    const int m = num_residuals();
    std::vector<J> out(m);
    if (!(*functor_)(amounts.data(), out.data())) return false;
    const std::size_t last = std::min(directions, first + N);
    for (int r = 0; r < m; ++r) {
      residuals[r] = out[r].a;
      for (std::size_t d = first; d < last; ++d)
        gradient[r * directions + d] = out[r].v[d - first];
    }
    return true;
  }

  std::unique_ptr<CaptureFunctor> functor_;
  std::vector<std::vector<Term>> terms_;  // per direction: the parameters it depends on
};

// A capture's whitened residuals `W r` (W from Rust, see FfiCapture): the autodiff cost
// gives r and ∂r/∂θ, and W is applied to both in double afterwards, which costs a small
// matrix product instead of carrying it through the Jets. The low-rank form
// `scale·(I − U·diag(shrink)·Uᵀ)` costs O(m·q) per column instead of O(m²).
class WhitenedCost : public ceres::CostFunction {
 public:
  WhitenedCost(ceres::CostFunction* raw, const double* w, int rank)
      : raw_(raw), w_(w), rank_(rank) {
    *mutable_parameter_block_sizes() = raw_->parameter_block_sizes();
    set_num_residuals(raw_->num_residuals());
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int m = num_residuals();
    const std::vector<std::int32_t>& sizes = parameter_block_sizes();
    std::vector<double> r(m);
    std::vector<std::vector<double>> jac;
    std::vector<double*> raw_jacobians;
    if (jacobians != nullptr) {
      jac.resize(sizes.size());
      raw_jacobians.assign(sizes.size(), nullptr);
      for (std::size_t b = 0; b < sizes.size(); ++b) {
        if (jacobians[b] == nullptr) continue;
        jac[b].resize(static_cast<std::size_t>(m) * sizes[b]);
        raw_jacobians[b] = jac[b].data();
      }
    }
    if (!raw_->Evaluate(parameters, r.data(),
                        jacobians != nullptr ? raw_jacobians.data() : nullptr))
      return false;
    apply(r.data(), residuals, m, 1);
    if (jacobians != nullptr)
      for (std::size_t b = 0; b < sizes.size(); ++b)
        if (jacobians[b] != nullptr) apply(raw_jacobians[b], jacobians[b], m, sizes[b]);
    return true;
  }

 private:
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

  // out = W · in, both m × cols row major.
  void apply(const double* in, double* out, int m, int cols) const {
    const Eigen::Map<const RowMajor> x(in, m, cols);
    Eigen::Map<RowMajor> y(out, m, cols);
    if (rank_ < 0) {
      y.noalias() = Eigen::Map<const RowMajor>(w_, m, m) * x;
      return;
    }
    const double scale = w_[0];
    const Eigen::Map<const RowMajor> u(w_ + 1, m, rank_);
    const Eigen::Map<const Eigen::VectorXd> shrink(w_ + 1 + static_cast<std::size_t>(m) * rank_, rank_);
    const RowMajor z = shrink.asDiagonal() * (u.transpose() * x);
    y.noalias() = scale * (x - u * z);
  }

  std::unique_ptr<ceres::CostFunction> raw_;
  const double* w_;
  int rank_;
};

// ---------------------------------------------------------------------------------------
// The ceres::Problem with its parameter block storage.

class Built {
 public:
  Built(const FfiProblem& p, const double* values, LossKind loss, double loss_scale)
      : layout_(make_layout(p)) {
    const int n = static_cast<int>(p.params.size());
    const int blocks = static_cast<int>(layout_.members.size());
    values_.resize(blocks);
    for (int b = 0; b < blocks; ++b)
      for (int g : layout_.members[b]) values_[b].push_back(values[g]);
    std::vector<bool> used(blocks, false);

    for (const FfiCapture& cap : p.captures) {
      if (cap.vertex_count == 0) continue;
      // The blocks this capture's steps reference, ascending.
      std::vector<bool> referenced(blocks, false);
      auto reference = [&](const FfiAmount& a) {
        for (int k = 0; k < kTerms; ++k)
          if (a.params[k] >= 0) referenced[layout_.block_of[a.params[k]]] = true;
      };
      const std::uint32_t steps = cap.camera_steps + cap.board_steps;
      for (std::uint32_t k = 0; k < steps; ++k) {
        const FfiStep& s = p.steps[cap.first_step + k];
        if (s.kind != StepKind::Fixed) reference(s.amount);
      }
      const FfiProjection& c = p.projections[cap.projection];
      for (const FfiAmount* a : {&c.fx, &c.fy, &c.cx, &c.cy, &c.k1, &c.k2}) reference(*a);
      // A capture that depends on no free parameter still contributes its (constant)
      // residuals: attach it to block 0, whose Jacobian columns it leaves zero.
      if (std::none_of(referenced.begin(), referenced.end(), [](bool r) { return r; }))
        referenced[0] = true;
      std::vector<int> slot(n, -1), offset(n, -1);
      std::vector<double*> pointers;
      std::vector<int> sizes;
      for (int b = 0; b < blocks; ++b) {
        if (!referenced[b]) continue;
        for (int g : layout_.members[b]) {
          slot[g] = static_cast<int>(pointers.size());
          offset[g] = layout_.offset_of[g];
        }
        pointers.push_back(values_[b].data());
        sizes.push_back(static_cast<int>(values_[b].size()));
        if (!used[b]) {
          used[b] = true;
          problem_.AddParameterBlock(values_[b].data(), sizes.back());
        }
      }

      const bool per_vertex = loss != LossKind::Squared;
      const std::uint32_t groups = per_vertex ? cap.vertex_count : 1;
      const std::uint32_t count = per_vertex ? 1 : cap.vertex_count;
      for (std::uint32_t g = 0; g < groups; ++g) {
        ceres::CostFunction* cost = new CaptureCost(
            std::make_unique<CaptureFunctor>(p, cap, g * count, count), sizes, slot, offset);
        // validate() rules out whitening together with a robust loss (per-vertex blocks).
        if (cap.first_weight >= 0)
          cost = new WhitenedCost(cost, p.weights.data() + cap.first_weight, cap.whitening_rank);
        ceres::LossFunction* loss_function = nullptr;
        if (loss == LossKind::Huber) loss_function = new ceres::HuberLoss(loss_scale);
        if (loss == LossKind::Cauchy) loss_function = new ceres::CauchyLoss(loss_scale);
        problem_.AddResidualBlock(cost, loss_function, pointers);
      }
    }
    for (int b = 0; b < blocks; ++b)
      if (used[b]) used_.push_back(b);
  }

  Built(const Built&) = delete;
  Built& operator=(const Built&) = delete;

  ceres::Problem& problem() { return problem_; }
  const Layout& layout() const { return layout_; }
  // Blocks some residual depends on, ascending (the others keep their start values).
  const std::vector<int>& used() const { return used_; }
  double* block(int b) { return values_[b].data(); }

  // The free parameters in their global order.
  rust::Vec<double> gather() const {
    rust::Vec<double> out;
    const std::size_t n = layout_.block_of.size();
    out.reserve(n);
    for (std::size_t g = 0; g < n; ++g)
      out.push_back(values_[layout_.block_of[g]][layout_.offset_of[g]]);
    return out;
  }

  // Global free-parameter index of each column when the used blocks are concatenated.
  std::vector<int> used_columns() const {
    std::vector<int> columns;
    for (int b : used_)
      for (int g : layout_.members[b]) columns.push_back(g);
    return columns;
  }

 private:
  Layout layout_;
  std::vector<std::vector<double>> values_;
  std::vector<int> used_;
  ceres::Problem problem_;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The Jacobian of the used blocks at the current values (weighted, robust loss applied),
// dense, one column per used free parameter (Built::used_columns); false when a vertex lies
// behind the camera.
bool dense_jacobian(Built& built, std::vector<double>* residuals, Eigen::MatrixXd& jacobian) {
  ceres::Problem::EvaluateOptions eo;
  for (int b : built.used()) eo.parameter_blocks.push_back(built.block(b));
  eo.num_threads = 1;
  double cost = 0.0;
  ceres::CRSMatrix crs;
  if (!built.problem().Evaluate(eo, &cost, residuals, nullptr, &crs)) return false;
  if (crs.num_cols != static_cast<int>(built.used_columns().size()))
    throw std::runtime_error("unexpected Jacobian shape from Ceres");
  jacobian.setZero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r)
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) jacobian(r, crs.cols[k]) = crs.values[k];
  return true;
}

}  // namespace

FfiSolution solve(const FfiProblem& problem, const FfiOptions& options) {
  try {
    const auto start = std::chrono::steady_clock::now();
    init_logging(options.verbose);
    validate(problem);
    validate(problem, options);
    Built built(problem, problem.params.data(), options.loss, options.loss_scale);

    ceres::Solver::Options so;
    so.minimizer_type = ceres::TRUST_REGION;
    so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    so.linear_solver_type = options.linear_solver == LinearSolver::DenseQr
                                ? ceres::DENSE_QR
                                : ceres::DENSE_NORMAL_CHOLESKY;
    so.max_num_iterations = static_cast<int>(std::min<std::uint32_t>(options.max_iterations,
                                                                     INT_MAX));
    so.function_tolerance = options.function_tolerance;
    so.gradient_tolerance = options.gradient_tolerance;
    so.parameter_tolerance = options.parameter_tolerance;
    so.num_threads = 1;
    so.logging_type = options.verbose ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
    so.minimizer_progress_to_stdout = false;  // progress goes to stderr through glog
    std::string invalid;
    if (!so.IsValid(&invalid)) fail("invalid solver options: " + invalid);

    ceres::Solver::Summary summary;
    ceres::Solve(so, &built.problem(), &summary);
    if (options.verbose) LOG(INFO) << summary.FullReport();
    if (summary.termination_type == ceres::FAILURE)
      throw std::runtime_error("Ceres failed: " + summary.message);

    FfiSolution out;
    out.params = built.gather();
    out.iterations = static_cast<std::uint32_t>(summary.num_successful_steps +
                                                summary.num_unsuccessful_steps);
    out.initial_cost = summary.initial_cost;
    out.final_cost = summary.final_cost;
    // Convergence means a finite cost at finite values: Ceres also "converges" when a NaN
    // gradient ends the search.
    bool finite_values = finite(summary.final_cost);
    for (double x : out.params) finite_values = finite_values && finite(x);
    out.converged = summary.termination_type == ceres::CONVERGENCE && finite_values;
    out.termination = rust::String(
        std::string(ceres::TerminationTypeToString(summary.termination_type)) + ": " +
        summary.message);
    out.seconds = seconds_since(start);
    return out;
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("ceres solve: ") + e.what());
  }
}

FfiEvaluation evaluate(const FfiProblem& problem, rust::Slice<const double> params) {
  try {
    init_logging(false);
    validate(problem);
    const std::size_t n = problem.params.size();
    if (params.size() != n)
      fail("got " + std::to_string(params.size()) + " values for " + std::to_string(n) +
           " free parameters");
    for (double x : params)
      if (!finite(x)) fail("a parameter value is not finite");
    Built built(problem, params.data(), LossKind::Squared, 0.0);

    std::vector<double> residuals;
    Eigen::MatrixXd jacobian;
    if (!dense_jacobian(built, &residuals, jacobian))
      fail("evaluation failed: a vertex lies behind the camera (x <= 0) at these values");
    const std::vector<int> columns = built.used_columns();
    const std::size_t m = residuals.size();
    std::vector<double> dense(m * n, 0.0);
    for (std::size_t r = 0; r < m; ++r)
      for (std::size_t c = 0; c < columns.size(); ++c)
        dense[r * n + columns[c]] = jacobian(static_cast<Eigen::Index>(r),
                                             static_cast<Eigen::Index>(c));
    double cost = 0.0;
    for (double x : residuals) cost += 0.5 * x * x;

    FfiEvaluation out;
    out.cost = cost;
    out.residuals.reserve(m);
    for (double x : residuals) out.residuals.push_back(x);
    out.jacobian.reserve(m * n);
    for (double x : dense) out.jacobian.push_back(x);
    return out;
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("ceres evaluate: ") + e.what());
  }
}

}  // namespace naocalib
