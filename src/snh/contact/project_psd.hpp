#pragma once
// The nearest positive semi-definite matrix to a symmetric pair Hessian: H = Q Λ Qᵀ → Q max(Λ, 0) Qᵀ
// (IPC projects each contact pair's Hessian this way before assembly, like snh's elastic Hessians with
// PsdProjection::clamp, docs/math.md §4; contact may not use the material layer, so the clamp lives here).
// The symmetric part ½(H + Hᵀ) is projected; a matrix already PSD comes back as that symmetric part.
#include "snh/contact/distance_core.hpp"

namespace snh::contact {

[[nodiscard]] Mat6 project_psd(const Mat6& H);
[[nodiscard]] MatN<9> project_psd(const MatN<9>& H);
[[nodiscard]] Mat12 project_psd(const Mat12& H);

}  // namespace snh::contact
