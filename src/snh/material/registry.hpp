#pragma once
// Every energy by name. AnyMaterial is a std::variant: the runtime choice is made once by std::visit,
// and the code inside the visit is monomorphic (docs/design.md: no virtual call per element).
#include <array>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>

#include "snh/material/arap.hpp"
#include "snh/material/corotated.hpp"
#include "snh/material/lame.hpp"
#include "snh/material/linear.hpp"
#include "snh/material/material.hpp"
#include "snh/material/neo_hookean.hpp"
#include "snh/material/neo_hookean_a.hpp"
#include "snh/material/neo_hookean_b.hpp"
#include "snh/material/psi_d.hpp"
#include "snh/material/psi_e.hpp"
#include "snh/material/stable_neo_hookean.hpp"
#include "snh/material/stable_neo_hookean_log.hpp"
#include "snh/material/stvk.hpp"

namespace snh {

using AnyMaterial = std::variant<StableNeoHookean, StableNeoHookeanLog, NeoHookean, NeoHookeanA, NeoHookeanB,
                                 PsiD, PsiE, Corotated, Arap, StVK, Linear>;

/// The names accepted by make_material, in the order of AnyMaterial.
[[nodiscard]] const std::array<std::string_view, std::variant_size_v<AnyMaterial>>& material_names();

/// A name that is not one of material_names(); the message lists the valid ones.
class UnknownMaterial : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// The energy called `name` with parameters `p`.
///   name           one of material_names()
///   p              Lamé parameters; used as given, or, when reparametrize is true, taken as the
///                  linear-elastic μ_L, λ_L and mapped by the energy's from_linear (docs/math.md §2)
/// Throws UnknownMaterial or ParameterError with a one-line message.
[[nodiscard]] AnyMaterial make_material(std::string_view name, const Lame& p, bool reparametrize = false);

/// The name of the energy held.
[[nodiscard]] std::string_view name_of(const AnyMaterial& m);

}  // namespace snh
