// The report's muscle fibres (report/fibres.hpp): each fibre's segment is its cell's affine map applied to
// the rest fibre, through the cell's centre; muscles.json is checked against the mesh and the frames.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include <nlohmann/json.hpp>

#include "snh/io/base64.hpp"
#include "snh/mesh/box.hpp"
#include "snh/report/fibres.hpp"
#include "snh/report/report.hpp"

namespace snh {
namespace {

using json = nlohmann::json;

std::vector<float> fibre_floats(const std::string& b64) {
  std::string bytes;
  EXPECT_TRUE(snh::base64_decode(b64, bytes));
  std::vector<float> out(bytes.size() / sizeof(float));
  std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}

TEST(ReportFibres, SegmentsFollowEachCellsMapAndActivationItsFrame) {
  const VolumeMesh tets = box_tets(1), hexes = box_hexes(2);
  for (const VolumeMesh* mesh : {&tets, &hexes}) {
    const json j = {{"regions", {{{"name", "fat"}, {"kind", "tissue"}, {"cells", {0}}},
                                 {{"name", "m"}, {"kind", "muscle"}, {"cells", {1, 0}}, {"fibre_directions", {{0, 0, 2}, {1, 1, 0}}},
                                  {"activation", {0.0, 0.25, 1.0}}}}}};
    const ReportFibres f(j, "muscles.json", *mesh, 3);
    ASSERT_EQ(f.count(), 2u);
    EXPECT_EQ(f.summary()["muscles"], json({"m"}));
    // An affine motion: every cell's best map is F itself.
    Eigen::Matrix3d F;
    F << 1.2, 0.1, 0.0, -0.2, 0.8, 0.3, 0.05, 0.0, 1.1;
    const Eigen::Vector3d b(0.5, -1.0, 2.0);
    const Eigen::Matrix3Xd x = (F * mesh->vertices).colwise() + b;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    const json frame = f.frame(1, x, lo, hi);
    EXPECT_EQ(frame["activation"], json({0.25}));
    const std::vector<float> s = fibre_floats(frame["segments"].get<std::string>());
    ASSERT_EQ(s.size(), 12u);
    const int cells[2] = {1, 0};
    const Eigen::Vector3d dirs[2] = {Eigen::Vector3d::UnitZ(), Eigen::Vector3d(1, 1, 0).normalized()};
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      for (Eigen::Index c = 0; c < mesh->cells.rows(); ++c) centre += x.col(mesh->cells(c, cells[k])) / double(mesh->cells.rows());
      const Eigen::Vector3d half = F * dirs[k] * 0.4 * std::cbrt(std::abs(cell_volume(*mesh, cells[k])));
      for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(s[6 * k + a], centre[a] - half[a], 1e-6);
        EXPECT_NEAR(s[6 * k + 3 + a], centre[a] + half[a], 1e-6);
      }
    }
  }
}

TEST(ReportFibres, AFileThatDoesNotFitIsNamedInOneLine) {
  const VolumeMesh mesh = box_hexes(2);
  const auto error = [&](const json& j, std::size_t frames = 2) {
    try {
      ReportFibres f(j, "m.json", mesh, frames);
    } catch (const ReportError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const json good = {{"regions", {{{"name", "m"}, {"kind", "muscle"}, {"cells", {1}}, {"fibre_directions", {{0, 0, 1}}}, {"activation", {0, 1}}}}}};
  EXPECT_EQ(error(good), "");
  EXPECT_EQ(error(json::array()), "m.json: not a muscles file: it needs a \"regions\" array");
  EXPECT_EQ(error(good, 3), "m.json: muscle \"m\": 2 activations for 3 frames");
  json bad = good;
  bad["regions"][0]["cells"] = {8};
  EXPECT_EQ(error(bad), "m.json: muscle \"m\": cell 8 is not one of the mesh's 8 cells");
  bad = good;
  bad["regions"][0]["fibre_directions"] = {{0, 0, 0}};
  EXPECT_EQ(error(bad), "m.json: muscle \"m\": fibre 0 is not a finite nonzero vector");
  bad = good;
  bad["regions"][0]["fibre_directions"] = {{0, 1}};
  EXPECT_EQ(error(bad), "m.json: muscle \"m\": fibre 0 is not 3 numbers");
  bad = good;
  bad["regions"][0]["activation"] = {0, 2};
  EXPECT_EQ(error(bad), "m.json: muscle \"m\": an activation is not in [0, 1]");
  bad = good;
  bad["regions"][0]["cells"] = {1, 2};
  EXPECT_EQ(error(bad), "m.json: muscle \"m\": cells and fibre_directions must be arrays of one length");
}

}  // namespace
}  // namespace snh
