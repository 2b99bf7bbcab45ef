#pragma once
// The JSON reader shared by the scene's section parsers (internal to setup/): reads the keys of one object,
// remembering which were used, so that unknown keys can be named; every error is one line,
// "FILE: PATH.KEY: what is wrong".
#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/setup/scene.hpp"

namespace snh::scene {

using json = nlohmann::json;

/// Every number a scene gives is finite and at most this in magnitude (sizes, coordinates, translations,
/// gravity, density, damping, scale factors, material parameters, times): a bound far beyond any physical
/// scene, low enough that products of a few such values stay finite (issue 13).
constexpr double max_magnitude = 1e15;

class Keys {
 public:
  Keys(const json& j, std::string path, const std::string& file) : j_(j), path_(std::move(path)), file_(file) {
    if (!j.is_object()) fail("expected an object");
  }
  [[noreturn]] void fail(const std::string& what, const std::string& key = "") const {
    const std::string where = key.empty() ? path_ : (path_.empty() ? key : path_ + "." + key);
    throw SceneError(fmt::format("{}: {}{}", file_, where.empty() ? "" : where + ": ", what));
  }
  std::string path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  [[nodiscard]] const std::string& file() const { return file_; }
  const json* get(const std::string& key) {
    used_.insert(key);
    const auto it = j_.find(key);
    return it == j_.end() ? nullptr : &*it;
  }
  bool has(const std::string& key) const { return j_.contains(key); }
  double number(const std::string& key, double fallback) {
    const json* v = get(key);
    if (!v) return fallback;
    if (!v->is_number() || !std::isfinite(v->get<double>())) fail("expected a finite number, got " + v->dump(), key);
    const double x = v->get<double>();
    if (!(std::abs(x) <= max_magnitude)) fail(fmt::format("must be at most {:g} in magnitude, got {:g}", max_magnitude, x), key);
    return x;
  }
  double positive(const std::string& key, double fallback) {
    const double v = number(key, fallback);
    if (!(v > 0.0)) fail(fmt::format("must be > 0, got {:g}", v), key);
    return v;
  }
  double non_negative(const std::string& key, double fallback) {
    const double v = number(key, fallback);
    if (!(v >= 0.0)) fail(fmt::format("must be >= 0, got {:g}", v), key);
    return v;
  }
  long long integer(const std::string& key, long long fallback, long long lo, long long hi) {
    const json* v = get(key);
    if (!v) return fallback;
    if (!v->is_number_integer()) fail("expected an integer, got " + v->dump(), key);
    const long long n = v->get<long long>();
    if (n < lo || n > hi) fail(fmt::format("must be from {} to {}, got {}", lo, hi, n), key);
    return n;
  }
  bool boolean(const std::string& key, bool fallback) {
    const json* v = get(key);
    if (!v) return fallback;
    if (!v->is_boolean()) fail("expected true or false, got " + v->dump(), key);
    return v->get<bool>();
  }
  std::string choice(const std::string& key, const std::string& fallback, const std::vector<std::string>& allowed) {
    const json* v = get(key);
    if (!v) return fallback;
    if (!v->is_string() || std::find(allowed.begin(), allowed.end(), v->get<std::string>()) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      fail(fmt::format("expected one of {}, got {}", list, v->dump()), key);
    }
    return v->get<std::string>();
  }
  std::optional<Eigen::Vector3d> vec3(const std::string& key) {
    const json* v = get(key);
    if (!v) return std::nullopt;
    if (!v->is_array() || v->size() != 3) fail("expected 3 numbers, got " + v->dump(), key);
    Eigen::Vector3d out;
    for (int i = 0; i < 3; ++i) {
      if (!(*v)[i].is_number() || !std::isfinite((*v)[i].get<double>())) fail("expected 3 finite numbers, got " + v->dump(), key);
      if (!(std::abs((*v)[i].get<double>()) <= max_magnitude))
        fail(fmt::format("expected 3 numbers at most {:g} in magnitude, got {}", max_magnitude, v->dump()), key);
      out[i] = (*v)[i].get<double>();
    }
    return out;
  }
  /// An axis: "x", "y" or "z".
  int axis(const std::string& key, const std::string& fallback) {
    const std::string a = choice(key, fallback, {"x", "y", "z"});
    return a[0] - 'x';
  }
  /// Throws for the first key that was never asked for.
  void finish() const {
    for (auto it = j_.begin(); it != j_.end(); ++it)
      if (!used_.count(it.key())) {
        std::string known;
        for (const auto& k : used_) known += (known.empty() ? "" : ", ") + k;
        fail(fmt::format("unknown key (known here: {})", known), it.key());
      }
  }

 private:
  const json& j_;
  std::string path_, file_;
  std::set<std::string> used_;
};


}  // namespace snh::scene
