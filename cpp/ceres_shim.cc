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
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <ceres/covariance.h>
#include <ceres/crs_matrix.h>
#include <ceres/dynamic_autodiff_cost_function.h>
#include <ceres/jet.h>
#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <ceres/types.h>
#include <Eigen/Core>
#include <glog/logging.h>

#include "naocalib/src/solve/ceres.rs.h"

namespace naocalib {
namespace {

// Jet width of the autodiff passes: a capture of the paper's model references at most
// camera (3) + leg (6) + board (3) = 12 free parameters, one pass; the extended model takes
// a few more passes.
constexpr int kStride = 12;

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
  const FfiProjection& c = p.projection;
  for (const FfiAmount* a : {&c.fx, &c.fy, &c.cx, &c.cy, &c.k1, &c.k2})
    validate(*a, n, "projection: ");
  for (double x : {c.p1, c.p2, c.k3})
    if (!finite(x)) fail("a distortion coefficient is not finite");

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

// One residual block: the vertices [first, first + count) of one capture.
class CaptureFunctor {
 public:
  CaptureFunctor(const FfiProblem& problem, const FfiCapture& capture, std::uint32_t first,
                 std::uint32_t count, std::vector<int> slot, std::vector<int> offset)
      : problem_(problem),
        capture_(capture),
        first_(first),
        count_(count),
        slot_(std::move(slot)),
        offset_(std::move(offset)) {
    const FfiProjection& c = problem.projection;
    for (const FfiAmount* a : {&c.fx, &c.fy, &c.cx, &c.cy, &c.k1, &c.k2})
      projection_free_ = projection_free_ || a->params[0] >= 0;
  }

  template <typename T>
  bool operator()(T const* const* parameters, T* residuals) const {
    Frame<T> camera, board;
    const FfiStep* steps = problem_.steps.data() + capture_.first_step;
    chain(steps, capture_.camera_steps, parameters, camera);
    chain(steps + capture_.camera_steps, capture_.board_steps, parameters, board);

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
      if (!project(pc, uv, parameters)) return false;
      out[2 * k] = uv[0] - pixels[2 * k];
      out[2 * k + 1] = uv[1] - pixels[2 * k + 1];
    }
    return true;
  }

 private:
  // `constant + Σ scale · α` (Affine::eval, same order of operations).
  template <typename T>
  T amount(const FfiAmount& a, T const* const* parameters) const {
    if (a.params[0] < 0) return T(a.constant);
    T value = parameters[slot_[a.params[0]]][offset_[a.params[0]]] * a.scales[0] + a.constant;
    for (int k = 1; k < kTerms; ++k)
      if (a.params[k] >= 0)
        value += parameters[slot_[a.params[k]]][offset_[a.params[k]]] * a.scales[k];
    return value;
  }

  // Chain::eval.
  template <typename T>
  void chain(const FfiStep* steps, std::uint32_t count, T const* const* parameters,
             Frame<T>& f) const {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) f.R[i][j] = T(i == j ? 1.0 : 0.0);
      f.t[i] = T(0.0);
    }
    for (std::uint32_t k = 0; k < count; ++k) {
      const FfiStep& s = steps[k];
      const int axis = static_cast<int>(s.axis);
      switch (s.kind) {
        case StepKind::Fixed:
          if (k == 0)
            set_fixed(f, s);
          else
            then_fixed(f, s);
          break;
        case StepKind::Rotate:
          rotate(f, axis, amount(s.amount, parameters));
          break;
        default:
          translate(f, axis, amount(s.amount, parameters));
          break;
      }
    }
  }

  // Projection::project_with: pinhole with optional OpenCV distortion (camera::distort);
  // false behind the camera.
  template <typename T>
  bool project(const T (&p)[3], T (&uv)[2], T const* const* parameters) const {
    if (value_of(p[0]) <= 0.0) return false;
    const FfiProjection& c = problem_.projection;
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
      const T k1 = amount(c.k1, parameters), k2 = amount(c.k2, parameters);
      const T p1 = T(c.p1), p2 = T(c.p2), k3 = T(c.k3);
      const T r2 = a * a + b * b;
      const T radial = T(1.0) + r2 * (k1 + r2 * (k2 + r2 * k3));
      const T ab = a * b;
      const T da = ab * p1 * 2.0 + (r2 + a * a * 2.0) * p2;
      const T db = (r2 + b * b * 2.0) * p1 + ab * p2 * 2.0;
      a = a * radial + da;
      b = b * radial + db;
    }
    uv[0] = a * amount(c.fx, parameters) + amount(c.cx, parameters);
    uv[1] = b * amount(c.fy, parameters) + amount(c.cy, parameters);
    return true;
  }

  const FfiProblem& problem_;
  const FfiCapture& capture_;
  std::uint32_t first_, count_;
  std::vector<int> slot_;    // per free parameter: its block's position in this block list
  std::vector<int> offset_;  // per free parameter: its position in the block
  bool projection_free_ = false;  // whether an intrinsic depends on a free parameter
};

using CaptureCost = ceres::DynamicAutoDiffCostFunction<CaptureFunctor, kStride>;

// A capture's whitened residuals `W r` (W from Rust, see FfiCapture): the autodiff cost
// gives r and ∂r/∂θ, and W is applied to both in double afterwards, which costs a small
// matrix product instead of carrying it through the Jets. The low-rank form
// `scale·(I − U·diag(shrink)·Uᵀ)` costs O(m·q) per column instead of O(m²).
class WhitenedCost : public ceres::CostFunction {
 public:
  WhitenedCost(CaptureCost* raw, const double* w, int rank)
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

  std::unique_ptr<CaptureCost> raw_;
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
      const FfiProjection& c = p.projection;
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
        auto* raw = new CaptureCost(new CaptureFunctor(p, cap, g * count, count, slot, offset));
        for (int size : sizes) raw->AddParameterBlock(size);
        raw->SetNumResiduals(static_cast<int>(2 * count));
        ceres::CostFunction* cost = raw;
        // validate() rules out whitening together with a robust loss (per-vertex blocks).
        if (cap.first_weight >= 0)
          cost = new WhitenedCost(raw, p.weights.data() + cap.first_weight, cap.whitening_rank);
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

// (JᵀJ)⁺ over all free parameters, row-major; zero rows/columns for parameters no
// residual depends on. Empty when Ceres cannot compute it.
bool covariance(Built& built, std::size_t n, rust::Vec<double>& out) {
  std::vector<const double*> blocks;
  for (int b : built.used()) blocks.push_back(built.block(b));
  // Sparse QR is fast but refuses a rank-deficient Jacobian; the dense SVD then gives the
  // pseudo-inverse, dropping directions with σ²_min/σ²_max below 1e-14.
  auto compute = [&](ceres::CovarianceAlgorithmType algorithm) {
    ceres::Covariance::Options options;
    options.algorithm_type = algorithm;
    options.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
    options.null_space_rank = -1;
    options.min_reciprocal_condition_number = 1e-14;
    options.num_threads = 1;
    auto cov = std::make_unique<ceres::Covariance>(options);
    if (!cov->Compute(blocks, &built.problem())) cov.reset();
    return cov;
  };
  std::unique_ptr<ceres::Covariance> cov = compute(ceres::SPARSE_QR);
  if (!cov) cov = compute(ceres::DENSE_SVD);
  if (!cov) return false;
  const std::vector<int> columns = built.used_columns();
  const std::size_t d = columns.size();
  std::vector<double> dense(d * d);
  if (!cov->GetCovarianceMatrix(blocks, dense.data())) return false;
  std::vector<double> full(n * n, 0.0);
  for (std::size_t i = 0; i < d; ++i)
    for (std::size_t j = 0; j < d; ++j) {
      const double x = dense[i * d + j];
      if (!finite(x)) return false;
      full[columns[i] * n + columns[j]] = x;
    }
  out.reserve(n * n);
  for (double x : full) out.push_back(x);
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
    so.linear_solver_type = ceres::DENSE_QR;
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
    out.covariance_ok = false;
    if (options.covariance) {
      rust::Vec<double> cov;
      if (covariance(built, problem.params.size(), cov)) {
        out.covariance = std::move(cov);
        out.covariance_ok = true;
      }
    }
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

    ceres::Problem::EvaluateOptions eo;
    for (int b : built.used()) eo.parameter_blocks.push_back(built.block(b));
    eo.num_threads = 1;
    double cost = 0.0;
    std::vector<double> residuals;
    ceres::CRSMatrix jacobian;
    if (!built.problem().Evaluate(eo, &cost, &residuals, nullptr, &jacobian))
      fail("evaluation failed: a vertex lies behind the camera (x <= 0) at these values");

    const std::vector<int> columns = built.used_columns();
    if (jacobian.num_cols != static_cast<int>(columns.size()) ||
        jacobian.num_rows != static_cast<int>(residuals.size()))
      throw std::runtime_error("unexpected Jacobian shape from Ceres");
    const std::size_t m = residuals.size();
    std::vector<double> dense(m * n, 0.0);
    for (std::size_t r = 0; r < m; ++r)
      for (int k = jacobian.rows[r]; k < jacobian.rows[r + 1]; ++k)
        dense[r * n + columns[jacobian.cols[k]]] = jacobian.values[k];

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
