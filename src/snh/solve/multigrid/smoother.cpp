// The smoother (multigrid.hpp): its values for each matrix (rows in sweep order, scaled node by node and
// stored in half precision; the inverses of the diagonal blocks), the nodal-block Gauss–Seidel sweeps
// (multi-colour in parallel, or lexicographic on one thread) in the scaled unknowns, the residual after the
// forward sweep, and the product A x from the lower block triangle. The inner loops use GCC's and Clang's
// vector extensions (AVX, FMA and F16C where the CPU has them).
#include <algorithm>
#include <cmath>
#include <cstring>

#if defined(__AVX__) || defined(__F16C__)
#include <immintrin.h>
#endif

#include <Eigen/Cholesky>

#include "snh/solve/multigrid/levels.hpp"

namespace snh {
namespace multigrid {
namespace {

/// Four doubles (GCC's and Clang's vector extensions; AVX on x86): a 3-vector in lanes 0–2, lane 3 unused.
using Lanes = double __attribute__((vector_size(32)));
using FloatLanes = float __attribute__((vector_size(16)));

#ifdef __F16C__
/// The four half-precision values from p on, as doubles.
inline Lanes widen4(const std::uint16_t* p) {
  std::int64_t bits;
  std::memcpy(&bits, p, sizeof bits);
  return Lanes(_mm256_cvtps_pd(_mm_cvtph_ps(_mm_cvtsi64_si128(bits))));
}
/// Nine values rounded to the nearest half-precision ones (their bits), saturated at ±65 504 (a NaN stays one:
/// min and max return their second operand where either is NaN).
inline void store_row_values(const float* v, std::uint16_t* to) {
  const __m256 largest = _mm256_set1_ps(65504.0f);
  const __m256 eight = _mm256_max_ps(-largest, _mm256_min_ps(largest, _mm256_loadu_ps(v)));
  _mm_storeu_si128(reinterpret_cast<__m128i*>(to), _mm256_cvtps_ph(eight, _MM_FROUND_TO_NEAREST_INT));
  to[8] = _cvtss_sh(std::clamp(v[8], -65504.0f, 65504.0f), _MM_FROUND_TO_NEAREST_INT);
}
#else
inline void store_row_values(const float* v, float* to) { std::copy(v, v + 9, to); }
#endif

/// The four floats from p on, as doubles.
[[maybe_unused]] inline Lanes widen4(const float* p) {
#ifdef __AVX__
  return Lanes(_mm256_cvtps_pd(_mm_loadu_ps(p)));  // GCC splits the generic form's load into halves
#else
  FloatLanes f;
  std::memcpy(&f, p, sizeof f);
  return __builtin_convertvector(f, Lanes);
#endif
}

inline Lanes lanes3(const double* p) { return Lanes{p[0], p[1], p[2], 0.0}; }
inline void store3(const Lanes& v, double* p) { p[0] = v[0], p[1] = v[1], p[2] = v[2]; }

/// t += a x lane by lane, one rounding (a fused multiply-add where the CPU has one).
inline Lanes multiply_add(const Lanes& a, double x, const Lanes& t) {
#ifdef __FMA__
  return Lanes(_mm256_fmadd_pd(__m256d(a), _mm256_set1_pd(x), __m256d(t)));
#else
  return t + a * x;
#endif
}

/// s −= Σ Â_ik x_k over row i's off-diagonal blocks `from` .. `to` (sweep_rows()), the scaled blocks stored
/// by columns in half (or single) precision: column j of a block, widened to four doubles (the fourth is the
/// value after it; it goes to the sums' unused lane), times x_kj. Six independent sums (the columns of the
/// even and of the odd blocks) with fused multiply-adds (one rounding and one instruction each): the loop is
/// not one chain of dependent additions, whose latency would bound it.
inline void subtract_row(const Level& L, int from, int to, const double* x, Lanes& s) {
  const RowValue* val = L.row_val.data() + 9 * static_cast<std::size_t>(from);
  const int* node = L.row_node.data();
  Lanes t0{}, t1{}, t2{}, u0{}, u1{}, u2{};
  int e = from;
  for (; e + 1 < to; e += 2, val += 18) {
    const double* xa = x + 3 * node[e];
    const double* xb = x + 3 * node[e + 1];
    t0 = multiply_add(widen4(val), xa[0], t0);
    t1 = multiply_add(widen4(val + 3), xa[1], t1);
    t2 = multiply_add(widen4(val + 6), xa[2], t2);
    u0 = multiply_add(widen4(val + 9), xb[0], u0);
    u1 = multiply_add(widen4(val + 12), xb[1], u1);
    u2 = multiply_add(widen4(val + 15), xb[2], u2);
  }
  if (e < to) {
    const double* xa = x + 3 * node[e];
    t0 = multiply_add(widen4(val), xa[0], t0);
    t1 = multiply_add(widen4(val + 3), xa[1], t1);
    t2 = multiply_add(widen4(val + 6), xa[2], t2);
  }
  s -= ((t0 + u0) + (t1 + u1)) + (t2 + u2);
}

/// x̂_i = D̂_i⁻¹ (b̂_i − Σ Â_ik x̂_k) over all blocks of row i (whole = true) or its first `before` (the others
/// meet x = 0), in the scaled unknowns (x̂ = x / σ, b̂ = σ b, Â = σ A σ): D̂_i⁻¹ = D_i⁻¹ / σ_i², both factors
/// applied as divisions by σ_i, a power of two (exact).
inline void relax_node(Level& L, int i, bool whole) {
  Lanes s = lanes3(L.b.data() + 3 * i);
  subtract_row(L, L.row_start[i], whole ? L.row_end[i] : L.row_start[i] + L.before[i], L.x.data(), s);
  const double to_unscaled = 1.0 / L.scale[static_cast<std::size_t>(i)];
  const double t[3] = {s[0] * to_unscaled, s[1] * to_unscaled, s[2] * to_unscaled};
  double* x = L.x.data() + 3 * i;
  solve_diagonal(L, i, t, x);
  for (int a = 0; a < 3; ++a) x[a] *= to_unscaled;
}

/// relax_node() for the nodes of colour c. Nodes of one colour are not coupled: they update in parallel,
/// each row's sum in its fixed order, so the result does not depend on the thread count.
void relax_colour(Level& L, int c, bool whole) {
  const int first = L.colour_start[c], last = L.colour_start[c + 1];
#pragma omp for schedule(static)
  for (int q = first; q < last; ++q) relax_node(L, L.by_colour[q], whole);
}

/// Four doubles from p on.
inline Lanes lanes4(const double* p) {
#ifdef __AVX__
  return Lanes(_mm256_loadu_pd(p));
#else
  Lanes v;
  std::memcpy(&v, p, sizeof v);
  return v;
#endif
}

}  // namespace

/// A forward lexicographic nodal-block Gauss–Seidel sweep for L.A x = L.b from x = 0 (the blocks of higher
/// nodes meet only zeros): the smoother of a lexicographic level.
void forward_sweep_in_order(Level& L) {
  L.x.setZero();
  for (int i = 0; i < L.nodes; ++i) relax_node(L, i, false);
}

/// The backward lexicographic sweep on L.x, nodes in descending order, whole rows.
void backward_sweep_in_order(Level& L) {
  for (int i = L.nodes - 1; i >= 0; --i) relax_node(L, i, true);
}

/// A forward multi-colour nodal-block Gauss–Seidel sweep for L.A x = L.b from x = 0, colour by colour: phase
/// by phase (Level::colour_phase), a large colour's nodes shared among the threads, a run of small colours
/// relaxed by one of them in colour order.
void forward_sweep(Level& L, bool parallel) {
  L.x.setZero();
  const int phases = static_cast<int>(L.colour_phase.size()) - 1;
#pragma omp parallel if (parallel)
  for (int p = 0; p < phases; ++p) {
    if (!L.small_colour(L.colour_phase[p])) {
      relax_colour(L, L.colour_phase[p], false);
      continue;
    }
#pragma omp single
    for (int q = L.colour_start[L.colour_phase[p]]; q < L.colour_start[L.colour_phase[p + 1]]; ++q) relax_node(L, L.by_colour[q], false);
  }
}

/// The backward sweep on L.x: the colours in reverse order (the forward sweep's adjoint, so that the
/// V-cycle is symmetric).
void backward_sweep(Level& L, bool parallel) {
  const int phases = static_cast<int>(L.colour_phase.size()) - 1;
#pragma omp parallel if (parallel)
  for (int p = phases - 1; p >= 0; --p) {
    if (!L.small_colour(L.colour_phase[p])) {
      relax_colour(L, L.colour_phase[p], true);
      continue;
    }
#pragma omp single
    for (int q = L.colour_start[L.colour_phase[p + 1]] - 1; q >= L.colour_start[L.colour_phase[p]]; --q) relax_node(L, L.by_colour[q], true);
  }
}

/// L.r = (L.b − Â L.x) / σ right after forward_sweep() (or forward_sweep_in_order()), row by row in parallel:
/// the residual of the unscaled equations, b − Ã x with Ã the smoother's matrix (half-precision off-diagonal
/// blocks: the sweeps' residuals are Ã's, so this one must be too for the V-cycle to stay symmetric). The
/// sweep made row i's equation hold with the lower colours' (nodes') final x̂ and the higher ones' zeros, so
/// only the blocks of higher colours (nodes) are left: r_i = −Σ Â_ik x̂_k / σ_i over them (equal in exact
/// arithmetic, half the blocks).
void forward_residual(Level& L, bool parallel) {
  const double* x = L.x.data();
#pragma omp parallel for schedule(static) if (parallel)
  for (int q = 0; q < L.nodes; ++q) {  // in sweep order, as the rows lie
    const int i = L.lexicographic ? q : L.by_colour[q];
    Lanes s{0.0, 0.0, 0.0, 0.0};
    subtract_row(L, L.row_start[i] + L.before[i], L.row_end[i], x, s);
    store3(s * (1.0 / L.scale[static_cast<std::size_t>(i)]), L.r.data() + 3 * i);
  }
}

/// Into the scaled unknowns before a level's sweeps: b̂ = σ b.
void scale_right_side(Level& L, bool parallel) {
#pragma omp parallel for schedule(static) if (parallel)
  for (int i = 0; i < L.nodes; ++i)
    for (int a = 0; a < 3; ++a) L.b[3 * i + a] *= L.scale[static_cast<std::size_t>(i)];
}

/// Out of them after the last sweep: x = σ x̂.
void unscale_solution(Level& L, bool parallel) {
#pragma omp parallel for schedule(static) if (parallel)
  for (int i = 0; i < L.nodes; ++i)
    for (int a = 0; a < 3; ++a) L.x[3 * i + a] *= L.scale[static_cast<std::size_t>(i)];
}

/// y = −A x from A's lower block triangle, by L's chunks in parallel: each
/// chunk's rows in order, then each row's sum and the chunks' spills into it in chunk order (a fixed order:
/// the result does not depend on the thread count). Four lanes at a time: a block's rows r_k (4 doubles from
/// each, the fourth the next row's first: it meets x's zero lane, or goes to the spill's unused one) give
/// row i's sums lane by lane, t_k += r_k ∘ x_j, added across the lanes at the row's end, and the spill
/// −= Σ_k r_k x_ik.
void subtract_product(Level& L, const double* x, double* y, bool parallel) {
  const double* val = L.A.val.data();
  const int chunks = static_cast<int>(L.chunk_low.size());
#pragma omp parallel if (parallel)
  {
#pragma omp for schedule(static)
    for (int c = 0; c < chunks; ++c) {
      double* spill = L.spill.data() + L.chunk_offset[c];
      const int low = L.chunk_low[c];
      std::fill(spill, L.spill.data() + L.chunk_offset[c + 1], 0.0);
      for (int i = L.chunk_start[c]; i < L.chunk_start[c + 1]; ++i) {
        const Lanes xi = lanes3(x + 3 * i);
        Lanes t0{}, t1{}, t2{};
        const int end = L.A.start[i + 1] - 1;  // the diagonal block
        for (int k = L.A.start[i]; k < end; ++k) {
          const double* a = val + 9 * static_cast<std::size_t>(k);
          const Lanes r0 = lanes4(a), r1 = lanes4(a + 3), r2 = lanes4(a + 6), xj = lanes3(x + 3 * L.A.col[k]);
          t0 += r0 * xj, t1 += r1 * xj, t2 += r2 * xj;
          double* to = spill + 3 * (L.A.col[k] - low);
          store3(lanes3(to) - (r0 * xi[0] + r1 * xi[1] + r2 * xi[2]), to);
        }
        const double* d = val + 9 * static_cast<std::size_t>(end);
        t0 += lanes4(d) * xi, t1 += lanes4(d + 3) * xi, t2 += lanes4(d + 6) * xi;
        const Lanes* t[3] = {&t0, &t1, &t2};
        for (int a = 0; a < 3; ++a) y[3 * i + a] = 0.0 - (((*t[a])[0] + (*t[a])[1]) + (*t[a])[2]);
      }
    }
#pragma omp for schedule(static)
    for (int i = 0; i < L.nodes; ++i)
      for (int c = 0; c < chunks; ++c)
        if (L.chunk_low[c] <= i && i < L.chunk_start[c + 1]) {
          const double* spill = L.spill.data() + L.chunk_offset[c] + 3 * (i - L.chunk_low[c]);
          for (int a = 0; a < 3; ++a) y[3 * i + a] += spill[a];
        }
  }
}

}  // namespace multigrid

using namespace multigrid;

/// The smoother's values for L's A: each node's scale σ_i, the rows' scaled blocks σ_i A_ik σ_k in row order
/// (read in a stream, each block as A_ik), and the inverses of the diagonal blocks' free parts (Cholesky:
/// false where a block is not positive definite, which proves that A is not).
///
/// σ_i is the largest power of two at most 1/√m_i, m_i the largest diagonal entry of node i's free DOFs. In a
/// positive definite A every entry satisfies |A_(ia,kb)| ≤ √(A_(ia,ia) A_(kb,kb)) ≤ √(m_i m_k), so every scaled
/// entry is at most 1: none overflows half precision (largest 65 504), and the largest ones lie where half
/// precision is finest (its relative rounding 2⁻¹¹). An indefinite matrix (a true Hessian) may have larger
/// entries: those saturate at ±65 504 (the smoother stays symmetric; conjugate gradients find the matrix's
/// negative curvature as they would). A power of two scales exactly.
bool MultigridPreconditioner::Impl::prepare_smoother(Level& L) {
  L.scale.resize(static_cast<std::size_t>(L.nodes));
  int failed = 0;  // nodes whose block is not positive definite (each node's inverse is its own: any order)
#pragma omp parallel for schedule(static) reduction(+ : failed) if (parallel(L))
  for (int i = 0; i < L.nodes; ++i) {
    Eigen::Matrix3d D = ConstBlock3(&L.A.val[9 * static_cast<std::size_t>(L.diagonal[i])]);
    double m = 0.0;
    for (int a = 0; a < 3; ++a) {
      if (L.free[3 * i + a]) m = std::max(m, D(a, a));
      else D(a, a) = 1.0;
    }
    double s = 1.0;
    if (m > 0.0 && std::isfinite(m)) {
      int exponent = 0;
      std::frexp(1.0 / std::sqrt(m), &exponent);  // 1/√m = f 2^exponent, f in [0.5, 1)
      s = std::ldexp(1.0, exponent - 1);
    }
    L.scale[static_cast<std::size_t>(i)] = s;
    const Eigen::LLT<Eigen::Matrix3d> llt(D);
    if (llt.info() != Eigen::Success || !(llt.matrixLLT().diagonal().array() > 0.0).all()) {
      ++failed;
      continue;
    }
    Eigen::Matrix3d inv = llt.solve(Eigen::Matrix3d::Identity());
    for (int a = 0; a < 3; ++a)
      if (!L.free[3 * i + a]) inv.row(a).setZero(), inv.col(a).setZero();
    Block3(&L.inverse[9 * static_cast<std::size_t>(i)]) = inv;
  }
  if (failed > 0) return false;  // A is not positive definite: no smoother for it
  L.row_val.resize(9 * L.row_slot.size() + 3);
  std::fill(L.row_val.end() - 3, L.row_val.end(), RowValue{0});
#pragma omp parallel for schedule(static) if (parallel(L))
  for (int i = 0; i < L.nodes; ++i)
    for (int e = L.row_start[i]; e < L.row_end[i]; ++e) {
      const double* a = &L.A.val[9 * static_cast<std::size_t>(L.row_slot[e])];  // row-major
      const int k = L.row_node[e];
      const double s = L.scale[static_cast<std::size_t>(i)] * L.scale[static_cast<std::size_t>(k)];
      float column_major[9];
      if (k < i) {  // A_ik stored: its transpose's rows are its columns
        for (int c = 0; c < 3; ++c)
          for (int r = 0; r < 3; ++r) column_major[3 * c + r] = static_cast<float>(s * a[3 * r + c]);
      } else {  // A_ki stored: its rows are A_ik's columns
        for (int j = 0; j < 9; ++j) column_major[j] = static_cast<float>(s * a[j]);
      }
      store_row_values(column_major, &L.row_val[9 * static_cast<std::size_t>(e)]);
    }
  return true;
}

}  // namespace snh
