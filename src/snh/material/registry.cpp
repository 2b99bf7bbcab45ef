#include "snh/material/registry.hpp"

#include <fmt/format.h>

#include "snh/material/printable.hpp"

namespace snh {
namespace {

template <std::size_t... I>
constexpr auto names_of(std::index_sequence<I...>) {
  return std::array<std::string_view, sizeof...(I)>{std::variant_alternative_t<I, AnyMaterial>::name...};
}

template <std::size_t I = 0>
AnyMaterial make_at(std::string_view name, const Lame& p, bool reparametrize) {
  if constexpr (I == std::variant_size_v<AnyMaterial>) {
    std::string list;
    for (auto n : material_names()) list += (list.empty() ? "" : ", ") + std::string(n);
    throw UnknownMaterial(fmt::format("unknown material '{}' (known: {})", printable(name), list));
  } else {
    using M = std::variant_alternative_t<I, AnyMaterial>;
    if (name == M::name) {
      if (reparametrize) {
        validate(p);
        return M(M::from_linear(p));
      }
      return M(p);
    }
    return make_at<I + 1>(name, p, reparametrize);
  }
}

}  // namespace

const std::array<std::string_view, std::variant_size_v<AnyMaterial>>& material_names() {
  static constexpr auto names = names_of(std::make_index_sequence<std::variant_size_v<AnyMaterial>>{});
  return names;
}

AnyMaterial make_material(std::string_view name, const Lame& p, bool reparametrize) {
  return make_at(name, p, reparametrize);
}

std::string_view name_of(const AnyMaterial& m) {
  return std::visit([](const auto& x) -> std::string_view { return std::decay_t<decltype(x)>::name; }, m);
}

static_assert([]<std::size_t... I>(std::index_sequence<I...>) {
  return (Material<std::variant_alternative_t<I, AnyMaterial>> && ...);
}(std::make_index_sequence<std::variant_size_v<AnyMaterial>>{}));

}  // namespace snh
