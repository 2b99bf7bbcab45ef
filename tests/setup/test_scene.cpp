// Scene files: every key checked (unknown keys and bad values named), initial deformations, scripted pin
// motion, and a starting state outside an energy's domain reported cleanly.
#include <gtest/gtest.h>

#include <unistd.h>

#include <csignal>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <tuple>
#include <utility>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/io/mesh_check.hpp"
#include "snh/run/interrupt.hpp"
#include "scene_error.hpp"
#include "snh/setup/scene_run.hpp"

namespace snh {
namespace {

using json = nlohmann::json;

using testing::error_of;

TEST(SceneFile, DefaultsAndAFullScene) {
  const Scene d = parse_scene(json::object(), "dir/empty.json");
  EXPECT_EQ(d.mesh.element, CellType::hex8);
  EXPECT_EQ(d.time.integrator, Integrator::backward_euler);
  EXPECT_EQ(d.output.dir, std::filesystem::path("output") / "empty");
  // The defaults live in the sections' structs: a scene built in code means what an empty file means.
  const Scene code;
  EXPECT_EQ(code.solver.tolerance, d.solver.tolerance);
  EXPECT_FALSE(d.solver.tolerance) << "scale-aware: no absolute rule unless given";
  EXPECT_EQ(code.solver.force_fraction, d.solver.force_fraction);
  EXPECT_EQ(code.solver.newton.relative_step_tolerance, d.solver.newton.relative_step_tolerance);
  EXPECT_GT(d.solver.newton.relative_step_tolerance, 0.0);
  // On the cube [-1, 1]³ of 64 hexes (l = 1/2) with E = 1e5: |g| < force_fraction E l².
  EXPECT_DOUBLE_EQ(newton_options(d.solver, box_hexes(4), 1e5).tolerance, d.solver.force_fraction * 1e5 / 4);
  EXPECT_EQ(code.time.dt, d.time.dt);
  EXPECT_EQ(code.time.frames, d.time.frames);
  EXPECT_EQ(code.material.name, d.material.name);
  EXPECT_EQ(code.material.params.lambda, d.material.params.lambda);
  EXPECT_EQ(code.mesh.resolution, d.mesh.resolution);
  const Scene s = parse_scene(json::parse(R"({
    "mesh": {"box": {"element": "tet", "res": 3, "tet_split": "mirrored", "min": [0, 0, 0], "max": [2, 1, 1]}},
    "material": {"name": "neo_hookean", "youngs": 1000, "poisson": 0.3, "reparametrize": true},
    "density": 2, "integrator": "quasi_static", "dt": 0.1, "end_time": 3, "frames": 6,
    "gravity": [0, 0, -1], "damping": {"mass": 0.5, "stiffness": 0.01},
    "pins": [{"indices": [0, 1], "motion": [{"type": "rotate", "axis": [0, 0, 2], "degrees": 90, "start": 1, "end": 2}]}],
    "initial": [{"type": "collapse", "to": "line", "axis": "x"}, {"type": "perturb", "amplitude": 0.01, "seed": 3}],
    "solver": {"linear": "pcg", "tolerance": 1e-6, "max_iterations": 20},
    "output": {"dir": "here", "vtu": false}})"),
                                  "full.json");
  EXPECT_EQ(s.mesh.element, CellType::tet4);
  EXPECT_EQ(s.mesh.tet_split, TetSplit::mirrored);
  EXPECT_EQ(s.material.name, "neo_hookean");
  EXPECT_TRUE(s.material.reparametrize);
  EXPECT_NEAR(s.material.params.mu, 1000 / 2.6, 1e-9);
  EXPECT_EQ(s.material.density, 2);
  EXPECT_EQ(s.time.integrator, Integrator::quasi_static);
  EXPECT_EQ(s.forces.stiffness_damping, 0.01);
  ASSERT_EQ(s.pins.size(), 1u);
  ASSERT_EQ(s.pins[0].motions.size(), 1u);
  const Rotate& rotate = std::get<Rotate>(s.pins[0].motions[0]);
  EXPECT_NEAR(rotate.radians, M_PI / 2, 1e-15);
  EXPECT_TRUE(rotate.axis.isApprox(Eigen::Vector3d(0, 0, 1)));
  EXPECT_EQ(rotate.start, 1);
  ASSERT_EQ(s.initial.size(), 2u);
  EXPECT_EQ(std::get<CollapseOp>(s.initial[0]).to, CollapseOp::To::line);
  EXPECT_EQ(std::get<PerturbOp>(s.initial[1]).seed, 3u);
  EXPECT_EQ(s.solver.linear, "pcg");
  EXPECT_EQ(s.solver.newton.max_iterations, 20);
  EXPECT_EQ(s.output.dir, "here");
  EXPECT_FALSE(s.output.vtu);
  EXPECT_EQ(s.solver.tolerance, 1e-6);
  // The build makes the body and resolves what depends on it; the given values stay.
  const BuiltScene b = build_scene(s);
  EXPECT_EQ(b.body->mesh.cell_count(), 6 * 27);
  EXPECT_EQ(b.end_time, 3);
  EXPECT_EQ(b.frames, 6);
  EXPECT_EQ(b.newton.tolerance, 1e-6);
  EXPECT_EQ(b.newton.max_iterations, 20);
  // An empty scene's defaults: 25 frames over 1 s, |g| < force_fraction E l² on the cube of 64 hexes (l = 1/2).
  const BuiltScene e = build_scene(d);
  EXPECT_EQ(e.end_time, TimeSpec::default_end_time);
  EXPECT_EQ(e.frames, TimeSpec::default_frames);
  EXPECT_DOUBLE_EQ(e.newton.tolerance, d.solver.force_fraction * youngs_modulus(d.material.params) / 4);
}

TEST(SceneFile, ParsingReadsNoFile) {
  // Pure: a scene naming files that do not exist parses; its build names the file that is missing.
  const Scene s = parse_scene(json::parse(R"({"mesh": {"file": "/nonexistent/mesh.msh"},
    "contact": {"dhat": 0.1, "stiffness": 1}, "colliders": [{"type": "mesh", "file": "/nonexistent/plate.obj"}]})"),
                              "s.json");
  EXPECT_EQ(s.mesh.file, "/nonexistent/mesh.msh");
  EXPECT_EQ(s.contact.colliders.at(0).triangles.cols(), 0) << "not read";
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": 1},
    "colliders": [{"type": "mesh", "file": "/nonexistent/plate.obj"}]})")).substr(0, 48),
            "s.json: colliders[0].file: /nonexistent/plate.ob");
  try {
    (void)build_scene(parse_scene(json::parse(R"({"mesh": {"file": "/nonexistent/mesh.msh"}})"), "s.json"));
    ADD_FAILURE() << "no error";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/mesh.msh"), std::string::npos) << e.what();
  }
  const Scene f = parse_scene(json::parse(R"({"flesh": {"model": "/nonexistent/model.glb"}})"), "s.json");
  EXPECT_EQ(f.flesh->model, "/nonexistent/model.glb");
  EXPECT_THROW((void)build_scene(f), std::exception);
}

TEST(SceneFile, ErrorsNameTheKey) {
  EXPECT_EQ(error_of(json::parse(R"({"gravty": [0, -9.8, 0]})")).substr(0, 34), "s.json: gravty: unknown key (known");
  EXPECT_NE(error_of(json::parse(R"({"pins": [{"regon": {}}]})")).find("s.json: pins[0]: give exactly one of region or indices"),
            std::string::npos);
  EXPECT_NE(error_of(json::parse(R"({"pins": [{"indices": [0], "motion": [{"type": "translate", "by": [1, 0, 0], "sped": 2}]}]})"))
                .find("s.json: pins[0].motion[0].sped: unknown key"),
            std::string::npos);
  EXPECT_EQ(error_of(json::parse(R"({"dt": -1})")), "s.json: dt: must be > 0, got -1");
  EXPECT_EQ(error_of(json::parse(R"({"frames": 2.5})")), "s.json: frames: expected an integer, got 2.5");
  EXPECT_EQ(error_of(json::parse(R"({"gravity": [0, 1]})")), "s.json: gravity: expected 3 numbers, got [0,1]");
  EXPECT_EQ(error_of(json::parse(R"({"integrator": "rk4"})")),
            "s.json: integrator: expected one of backward_euler, bdf2, tr_bdf2, quasi_static, got \"rk4\"");
  EXPECT_NE(error_of(json::parse(R"({"material": {"name": "stable_neohookean"}})")).find("s.json: material: unknown material"),
            std::string::npos);
  EXPECT_NE(error_of(json::parse(R"({"material": {"name": "snh\u0000x"}})"))
                .find("unknown material 'snh\\x00x' (known: stable_neo_hookean"),
            std::string::npos);
  EXPECT_EQ(error_of(json::parse(R"({"material": {"mu": 1, "youngs": 3, "poisson": 0.2}})")),
            "s.json: material: give mu and lambda, or youngs and poisson, not both");
  EXPECT_NE(error_of(json::parse(R"({"material": {"youngs": 3, "poisson": 0.5}})")).find("Poisson's ratio must satisfy"),
            std::string::npos);
  EXPECT_EQ(error_of(json::parse(R"({"pins": [{"indices": [125]}]})")),
            "s.json: pins[0]: vertex index 125 is out of range (the mesh has 125 vertices)");
  EXPECT_EQ(error_of(json::parse(R"({"pins": [{"region": {"min": [5, 5, 5], "max": [6, 6, 6]}}]})")),
            "s.json: pins[0]: the region selects no vertex");
  EXPECT_EQ(error_of(json::parse(R"({"mesh": {"box": {"res": 0}}})")), "s.json: mesh.box.res: must be from 1 to 400, got 0");
  EXPECT_EQ(error_of(json::parse(R"({"initial": [{"type": "reflect", "axis": "w"}]})")),
            "s.json: initial[0].axis: expected one of x, y, z, got \"w\"");
  EXPECT_EQ(error_of(json::parse("[1, 2]")), "s.json: expected an object");
}

TEST(SceneFile, ContactNeedsASeparatedStart) {
  // The default box spans [-1, 1]³: a plane through it is refused before the run, naming the vertex.
  const std::string contact = R"("contact": {"dhat": 0.01, "stiffness": 1e3}, )";
  const std::string error = error_of(json::parse("{" + contact + R"("colliders": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0]}]})"));
  EXPECT_EQ(error.substr(0, 39), "s.json: colliders[0]: vertex 0 of the m") << error;
  EXPECT_NE(error.find("-1 from the plane, on or behind it at the start"), std::string::npos) << error;
  // Touching the plane is refused too; just above it is fine.
  EXPECT_NE(error_of(json::parse("{" + contact + R"("colliders": [{"type": "plane", "point": [0, -1, 0], "normal": [0, 1, 0]}]})")),
            "");
  EXPECT_NO_THROW((void)build_scene(
      parse_scene(json::parse("{" + contact + R"("colliders": [{"type": "plane", "point": [0, -1.001, 0], "normal": [0, 1, 0]}]})"),
                  "s.json")));
}

TEST(SceneFile, SelfContactNeedsASurfaceThatDoesNotTouchItself) {
  // Two tets, the second's apex at the first's vertex (3) but a vertex of its own (8): distance 0 at the start.
  const auto dir = std::filesystem::temp_directory_path() / ("snh_test_scene_touch_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "touch.node") << "8 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
                                       "5 0 0 2\n6 1 0 2\n7 0 1 2\n8 0 0 1\n";
  std::ofstream(dir / "touch.ele") << "2 4 0\n1 1 2 3 4\n2 5 7 6 8\n";
  const std::string scene = R"({"mesh": {"file": "touch.ele"}, "contact": {"self": true, "dhat": 0.01, "stiffness": 1e3}})";
  try {
    (void)build_scene(parse_scene(json::parse(scene), dir / "s.json"));
    ADD_FAILURE() << "no error";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("contact.self: the mesh's surface touches itself at the start"), std::string::npos) << e.what();
  }
  // Apart (the second tet lifted by 0.5), the same scene is accepted.
  std::ofstream(dir / "touch.node") << "8 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
                                       "5 0 0 2.5\n6 1 0 2.5\n7 0 1 2.5\n8 0 0 1.5\n";
  EXPECT_NO_THROW((void)build_scene(parse_scene(json::parse(scene), dir / "s.json")));
  std::filesystem::remove_all(dir);
}

TEST(SceneFile, ContactKeysAreChecked) {
  const Scene s = parse_scene(json::parse(R"({"contact": {"self": true, "dhat": 0.01, "stiffness": 1e6},
    "colliders": [{"type": "plane", "point": [0, -2, 0], "normal": [0, 2, 0]}]})"), "s.json");
  EXPECT_TRUE(s.contact.enabled);
  EXPECT_TRUE(s.contact.self);
  EXPECT_EQ(s.contact.dhat, 0.01);
  EXPECT_EQ(s.contact.stiffness, 1e6);
  ASSERT_EQ(s.contact.planes.size(), 1u);
  EXPECT_EQ(s.contact.planes[0].normal, Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"self": true, "stiffness": 1}})")),
            "s.json: contact.dhat: required: the distance below which surfaces repel (> 0)");
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"dhat": -1, "stiffness": 1}})")), "s.json: contact.dhat: must be > 0, got -1");
  // kappa left out (or "auto") is chosen by the build: IPC's rule with backward Euler, E l / dhat^2
  // quasi-statically (l the cells' size), and the header says which.
  const Scene quasi = parse_scene(json::parse(R"({"integrator": "quasi_static", "contact": {"dhat": 0.1}})"), "s.json");
  EXPECT_FALSE(quasi.contact.stiffness);
  const BuiltScene qb = build_scene(quasi);
  const double cell = std::cbrt(std::abs(mesh_volume(qb.body->mesh)) / static_cast<double>(qb.body->mesh.cell_count()));
  EXPECT_NEAR(qb.contact.stiffness, youngs_modulus(quasi.material.params) * cell / 0.01, 1e-9 * qb.contact.stiffness);
  EXPECT_EQ(qb.contact_stiffness_rule, "chosen as E l / dhat^2, l the cells' size");
  const Scene automatic = parse_scene(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": "auto"}})"), "s.json");
  EXPECT_FALSE(automatic.contact.stiffness) << "auto: resolved by the build";
  EXPECT_GT(build_scene(automatic).contact.stiffness, 0.0);
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": "soft"}})")),
            "s.json: contact.stiffness: expected a number > 0 or \"auto\", got \"soft\"");
  EXPECT_EQ(build_scene(automatic).contact_stiffness_rule, "chosen by IPC's rule on the mesh's size, mass and time step");
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": 0}})")), "s.json: contact.stiffness: must be > 0, got 0");
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": 1, "self": 1}})")),
            "s.json: contact.self: expected true or false, got 1");
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": 1, "speed": 0.3}})")),
            "s.json: contact.speed: unknown key (known here: bones, dhat, friction, friction_velocity, self, stiffness)");
  // Friction: μ ≥ 0, its sticking velocity > 0 and only with μ > 0, and a plane or shape to act against.
  const std::string ground = R"(, "colliders": [{"type": "plane", "point": [0, -2, 0], "normal": [0, 1, 0]}]})";
  const Scene f = parse_scene(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": 1, "friction": 0.3, "friction_velocity": 0.01})" + ground),
                              "s.json");
  EXPECT_EQ(f.contact.friction, 0.3);
  EXPECT_EQ(f.contact.friction_velocity, 0.01);
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": 1, "friction": -0.3})" + ground)),
            "s.json: contact.friction: must be >= 0, got -0.3");
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": 1, "friction": "high"})" + ground)),
            "s.json: contact.friction: expected a finite number, got \"high\"");
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": 1, "friction": 0.3, "friction_velocity": 0})" + ground)),
            "s.json: contact.friction_velocity: must be > 0, got 0");
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": 1, "friction_velocity": 0.1})" + ground)),
            "s.json: contact.friction_velocity: has no effect without friction > 0");
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": 1, "friction": 0.3}})")),
            "s.json: contact.friction: acts in self-contact and against plane, sphere, capsule and box colliders, and this scene has "
            "none of them (mesh colliders are frictionless)");
  EXPECT_EQ(parse_scene(json::parse(R"({"contact": {"self": true, "dhat": 0.1, "stiffness": 1, "friction": 0.3}})"), "s.json").contact.friction,
            0.3);
  EXPECT_EQ(error_of(json::parse(R"({"contact": {"dhat": 0.1, "stiffness": 1, "bones": true}})")),
            "s.json: contact.bones: only a flesh scene has bones");
  const std::string contact = R"("contact": {"dhat": 0.1, "stiffness": 1}, )";
  EXPECT_EQ(error_of(json::parse("{" + contact + R"("colliders": {"type": "plane"}})")),
            "s.json: colliders: expected an array of colliders, got {\"type\":\"plane\"}");
  EXPECT_EQ(error_of(json::parse("{" + contact + R"("colliders": [{"type": "cone"}]})")),
            "s.json: colliders[0].type: expected one of plane, sphere, capsule, box, mesh, got \"cone\"");
  EXPECT_EQ(error_of(json::parse("{" + contact + R"("colliders": [{"point": [0, 0, 0], "normal": [0, 1, 0]}]})")),
            "s.json: colliders[0].type: required: the collider's type (plane, sphere, capsule, box or mesh)");
  EXPECT_EQ(error_of(json::parse("{" + contact + R"("colliders": [{"type": "plane", "normal": [0, 1, 0]}]})")),
            "s.json: colliders[0].point: required: a point of the plane, 3 numbers");
  EXPECT_EQ(error_of(json::parse("{" + contact + R"("colliders": [{"type": "plane", "point": [0, 0, 0]}]})")),
            "s.json: colliders[0].normal: required: the plane's normal (the side kept free), 3 numbers");
  EXPECT_EQ(error_of(json::parse("{" + contact + R"("colliders": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 0]}]})")),
            "s.json: colliders[0].normal: must not be zero");
  EXPECT_EQ(error_of(json::parse("{" + contact + R"("colliders": [{"type": "plane", "point": [0, 0], "normal": [0, 1, 0]}]})")),
            "s.json: colliders[0].point: expected 3 numbers, got [0,0]");
  EXPECT_EQ(error_of(json::parse("{" + contact +
                                 R"("colliders": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "spin": []}]})"))
,
            "s.json: colliders[0].spin: unknown key (known here: motion, normal, point, type)");
  EXPECT_EQ(error_of(json::parse(R"({"colliders": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0]}]})")),
            "s.json: colliders: colliders need a \"contact\" section (its dhat and stiffness)");
}

TEST(SceneFile, ShapeAndMeshCollidersAreCheckedKeyByKeyAndNeedASeparatedStart) {
  const std::string contact = R"("contact": {"dhat": 0.1, "stiffness": 1}, )";
  const auto colliders = [&](const std::string& list) { return json::parse("{" + contact + R"("colliders": )" + list + "}"); };
  // Accepted: each type away from the box [-1, 1]³, with motions.
  const auto obj = std::filesystem::temp_directory_path() / ("snh_collider_" + std::to_string(::getpid()) + ".obj");
  {
    std::ofstream f(obj);
    f << "v -3 2 -3\nv 3 2 -3\nv 3 2 3\nv -3 2 3\nf 1 2 3\nf 1 3 4\n";
  }
  const BuiltScene b = build_scene(parse_scene(colliders(R"([{"type": "sphere", "center": [0, 3, 0], "radius": 1.5,
      "motion": [{"type": "translate", "by": [0, -1, 0]}]},
    {"type": "capsule", "a": [-3, 0, 0], "b": [-3, 0, 2], "radius": 0.5},
    {"type": "box", "center": [3, 0, 0], "size": [1, 2, 3], "motion": [{"type": "rotate", "axis": [0, 1, 0], "degrees": 30}]},
    {"type": "plane", "point": [0, -2, 0], "normal": [0, 1, 0], "motion": [{"type": "translate", "by": [0, 0.5, 0]}]},
    {"type": "plane", "point": [0, -3, 0], "normal": [0, 1, 0]},
    {"type": "mesh", "file": ")" + obj.string() + R"(", "motion": [{"type": "scale", "factors": [1, 2, 1]}]}])"),
                                                "s.json"));
  const Scene& s = b.scene;
  ASSERT_EQ(s.contact.colliders.size(), 5u);
  ASSERT_EQ(s.contact.planes.size(), 1u);
  EXPECT_EQ(s.contact.planes[0].index, 4);
  EXPECT_EQ(s.contact.colliders[2].b, Eigen::Vector3d(0.5, 1, 1.5));  // half of the size
  EXPECT_EQ(s.contact.colliders[4].triangles.cols(), 2);
  EXPECT_EQ(s.contact.colliders[0].motions.size(), 1u);
  // Every key's refusal names it.
  EXPECT_EQ(error_of(colliders(R"([{"type": "sphere", "radius": 1}])")), "s.json: colliders[0].center: required: the sphere's centre, 3 numbers");
  EXPECT_EQ(error_of(colliders(R"([{"type": "sphere", "center": [0, 5, 0]}])")), "s.json: colliders[0].radius: required: the sphere's radius (> 0)");
  EXPECT_EQ(error_of(colliders(R"([{"type": "sphere", "center": [0, 5, 0], "radius": -1}])")), "s.json: colliders[0].radius: must be > 0, got -1");
  EXPECT_EQ(error_of(colliders(R"([{"type": "capsule", "a": [0, 5, 0], "radius": 1}])")),
            "s.json: colliders[0].b: required: the other end of the capsule's segment, 3 numbers");
  EXPECT_EQ(error_of(colliders(R"([{"type": "box", "center": [0, 5, 0], "size": [1, 0, 1]}])")),
            "s.json: colliders[0].size: expected 3 edge lengths > 0, got [1, 0, 1]");
  EXPECT_EQ(error_of(colliders(R"([{"type": "box", "center": [0, 5, 0], "size": [1, 1, 1], "half_extents": [1, 1, 1]}])")),
            "s.json: colliders[0].half_extents: unknown key (known here: center, motion, size, type)");
  EXPECT_EQ(error_of(colliders(R"([{"type": "sphere", "center": [0, 5, 0], "radius": 1, "motion": [{"type": "scale", "factors": [1, 2, 1]}]}])")),
            "s.json: colliders[0].motion[0].factors: a sphere collider scales only with three equal factors (a mesh collider takes any)");
  EXPECT_EQ(error_of(colliders(R"([{"type": "sphere", "center": [0, 5, 0], "radius": 1, "motion": [{"type": "spin"}]}])")),
            "s.json: colliders[0].motion[0].type: expected one of translate, rotate, scale, got \"spin\"");
  EXPECT_EQ(error_of(colliders(R"([{"type": "mesh"}])")),
            "s.json: colliders[0].file: required: the collider's surface file (.obj, .off, .ply or .stl)");
  EXPECT_EQ(error_of(colliders(R"([{"type": "mesh", "file": "plate.txt"}])")),
            "s.json: colliders[0].file: expected a .obj, .off, .ply or .stl file, got \"plate.txt\"");
  EXPECT_EQ(error_of(colliders(R"([{"type": "mesh", "file": "/nonexistent/plate.obj"}])")).substr(0, 48),
            "s.json: colliders[0].file: /nonexistent/plate.ob");
  // A start that is not separated, for each type (the box's surface vertices are on its faces).
  const auto starts_inside = [&](const std::string& collider, const std::string& what) {
    const std::string e = error_of(colliders("[" + collider + "]"));
    EXPECT_NE(e.find(what), std::string::npos) << e;
    EXPECT_EQ(e.substr(0, 22), "s.json: colliders[0]: ") << e;
  };
  starts_inside(R"({"type": "sphere", "center": [0, 1.5, 0], "radius": 0.6})", "from the sphere, on or inside it at the start");
  starts_inside(R"({"type": "capsule", "a": [-3, 0, 0], "b": [3, 0, 0], "radius": 0.2})", "from the capsule, on or inside it at the start");
  starts_inside(R"({"type": "box", "center": [1.5, 1.5, 0], "size": [1.2, 1.2, 1]})", "from the box, on or inside it at the start");
  starts_inside(R"({"type": "plane", "point": [0, -1, 0], "normal": [0, 1, 0], "motion": [{"type": "translate", "by": [0, 1, 0]}]})",
                "from the plane, on or inside it at the start");
  {
    std::ofstream f(obj);  // a triangle through the top face's corner (1, 1, 1)
    f << "v 1 1 1\nv 3 1 1\nv 1 3 1\nf 1 2 3\n";
  }
  starts_inside(R"({"type": "mesh", "file": ")" + obj.string() + R"("})", "the mesh's surface touches the collider's");
  std::filesystem::remove(obj);
}

TEST(SceneFile, UnreadableAndMalformedFiles) {
  EXPECT_THROW((void)load_scene("/nonexistent/scene.json"), SceneError);
  const auto path = std::filesystem::temp_directory_path() / ("snh_bad_scene_" + std::to_string(::getpid()) + ".json");
  std::ofstream(path) << "{\"dt\": 0.1,";
  try {
    (void)load_scene(path);
    ADD_FAILURE() << "no error";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line";
  }
  std::filesystem::remove(path);
}

TEST(SceneFile, InitialDeformations) {
  Scene s = parse_scene(json::parse(R"({"mesh": {"box": {"res": 2}}})"), "s.json");
  const VolumeMesh mesh = scene_body(s)->mesh;
  auto positions = [&](const char* ops) {
    s.initial = parse_scene(json::parse(std::string(R"({"mesh": {"box": {"res": 2}}, "initial": )") + ops + "}"), "s.json").initial;
    const Eigen::VectorXd x = initial_positions(s, mesh);
    return Eigen::Matrix3Xd(Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, mesh.vertex_count()));
  };
  const Eigen::Matrix3Xd& X = mesh.vertices;
  Eigen::Matrix3Xd R = X;
  R.row(0) *= -1.0;
  EXPECT_TRUE(positions(R"([{"type": "reflect", "axis": "x"}])").isApprox(R));
  EXPECT_TRUE(positions(R"([{"type": "scale", "factors": [2, 1, 0.5], "center": [1, 0, 0]}])")
                  .isApprox((Eigen::Vector3d(2, 1, 0.5).asDiagonal() * (X.colwise() - Eigen::Vector3d(1, 0, 0))).colwise() +
                            Eigen::Vector3d(1, 0, 0)));
  const Eigen::Matrix3Xd plane = positions(R"([{"type": "collapse", "to": "plane", "axis": "z"}])");
  EXPECT_EQ(plane.row(2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_TRUE(plane.topRows(2).isApprox(X.topRows(2)));
  const Eigen::Matrix3Xd line = positions(R"([{"type": "collapse", "to": "line", "axis": "y"}])");
  EXPECT_EQ(line.row(0).cwiseAbs().maxCoeff() + line.row(2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_TRUE(line.row(1).isApprox(X.row(1)));
  EXPECT_EQ(positions(R"([{"type": "collapse"}])").cwiseAbs().maxCoeff(), 0.0);
  const Eigen::Matrix3Xd p1 = positions(R"([{"type": "perturb", "amplitude": 0.1, "seed": 4}])");
  const Eigen::Matrix3Xd p2 = positions(R"([{"type": "perturb", "amplitude": 0.1, "seed": 4}])");
  const Eigen::Matrix3Xd p3 = positions(R"([{"type": "perturb", "amplitude": 0.1, "seed": 5}])");
  EXPECT_EQ(p1, p2) << "the same seed gives the same perturbation";
  EXPECT_NE(p1, p3);
  EXPECT_LE((p1 - X).cwiseAbs().maxCoeff(), 0.1);
  EXPECT_GT((p1 - X).cwiseAbs().maxCoeff(), 0.05);
  const Eigen::Matrix3Xd moved = positions(R"([{"type": "move", "indices": [13], "by": [0, 0, 1.5]}])");
  EXPECT_TRUE(moved.col(13).isApprox(X.col(13) + Eigen::Vector3d(0, 0, 1.5)));
  EXPECT_EQ((moved - X).cwiseAbs().sum(), 1.5) << "only vertex 13 moved";
}

/// Runs a scene quietly in a temporary directory.
SceneResult run_json(const std::string& text, const std::string& name) {
  Scene s = parse_scene(json::parse(text), name + ".json");
  s.output.dir = std::filesystem::temp_directory_path() / ("snh_test_scene_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(s.output.dir);
  std::ostringstream log;
  SceneResult r = run_scene(s, log);
  EXPECT_TRUE(std::filesystem::exists(s.output.dir / "stats.json"));
  EXPECT_TRUE(std::filesystem::exists(s.output.dir / "000.obj"));
  std::filesystem::remove_all(s.output.dir);
  return r;
}

TEST(SceneRun, PinsFollowTheirScript) {
  // A quasi-static twist: the top layer turns 90° about y between t = 0 and 1, the bottom holds.
  const SceneResult r = run_json(R"({
    "mesh": {"box": {"element": "hex", "res": 2}}, "integrator": "quasi_static", "end_time": 2, "frames": 4,
    "pins": [{"region": {"min": [-1, -1, -1], "max": [1, -1, 1]}},
             {"region": {"min": [-1, 1, -1], "max": [1, 1, 1]},
              "motion": [{"type": "rotate", "axis": [0, 1, 0], "degrees": 90, "end": 1},
                         {"type": "translate", "by": [0, 0.5, 0], "start": 1, "end": 2}]}]})",
                                 "twist");
  ASSERT_TRUE(r.all_converged) << r.failure;
  // Lattice vertex (2, 2, 1) = (1, 1, 0) turns to (0, 1, −1), then rises by 0.5.
  const int v = 2 + 2 * 3 + 1 * 9;
  EXPECT_TRUE(r.final_positions.segment<3>(3 * v).isApprox(Eigen::Vector3d(0, 1.5, -1), 1e-12));
  EXPECT_TRUE(r.final_positions.segment<3>(0).isApprox(Eigen::Vector3d(-1, -1, -1), 1e-12)) << "the bottom holds";
}

TEST(SceneRun, AStartOutsideTheDomainIsReportedNotCrashed) {
  const std::string inverted = R"({"mesh": {"box": {"res": 2}}, "material": {"name": "%s"},
    "initial": [{"type": "reflect", "axis": "x"}], "frames": 2, "end_time": 0.1})";
  auto scene = [&](const char* material) {
    std::string t = inverted;
    t.replace(t.find("%s"), 2, material);
    return t;
  };
  const SceneResult bad = run_json(scene("neo_hookean"), "inverted_log");
  EXPECT_FALSE(bad.all_converged);
  EXPECT_NE(bad.failure.find("initial state is outside the domain of neo_hookean"), std::string::npos) << bad.failure;
  ASSERT_EQ(bad.frames.size(), 1u);
  EXPECT_EQ(bad.frames[0].inverted, 8);
  EXPECT_TRUE(bad.final_positions.allFinite());
  // An inversion-safe energy simply runs from the inverted start.
  const SceneResult good = run_json(scene("stable_neo_hookean"), "inverted_snh");
  EXPECT_TRUE(good.all_converged) << good.failure;
  EXPECT_EQ(good.frames.size(), 3u);
}

TEST(SceneRun, ACubeFallsOntoAPlaneColliderAndStaysAboveIt) {
  // A cube of tets dropped 0.3 above the ground with self-contact on: it lands and rests on the barrier,
  // with κ given and with IPC's automatic choice.
  for (const char* stiffness : {"1e8", "\"auto\""}) {
  const double ground = -1.3, dhat = 0.02;
  const SceneResult r = run_json(fmt::format(R"({{
    "mesh": {{"box": {{"element": "tet", "res": 2}}}}, "material": {{"youngs": 1e5, "poisson": 0.3}}, "density": 100,
    "gravity": [0, -9.8, 0], "dt": 0.01, "end_time": 1.5, "frames": 15,
    "contact": {{"self": true, "dhat": {}, "stiffness": {}}},
    "colliders": [{{"type": "plane", "point": [0, {}, 0], "normal": [0, 1, 0]}}]}})",
                                             dhat, stiffness, ground),
                                 "drop");
  ASSERT_TRUE(r.all_converged) << stiffness << ": " << r.failure;
  double bottom = INFINITY;
  for (Eigen::Index v = 0; v < r.final_positions.size() / 3; ++v) bottom = std::min(bottom, r.final_positions[3 * v + 1]);
  EXPECT_GT(bottom, ground) << stiffness;
  EXPECT_LT(bottom, ground + dhat) << stiffness;  // resting on the ground (it fell 0.3)
  // The contact statistics: nothing in range at the start, the resting cube's bottom vertices in range at
  // the end (a distance in (0, d̂)), CCD run in between.
  EXPECT_EQ(r.frames.front().contact_pairs, 0);
  EXPECT_GT(r.frames.back().contact_pairs, 0);
  EXPECT_GT(r.frames.back().min_contact_distance, 0.0);
  EXPECT_LT(r.frames.back().min_contact_distance, dhat);
  EXPECT_NEAR(r.frames.back().min_contact_distance, bottom - ground, 1e-12);
  int ccd = 0;
  for (const FrameStats& f : r.frames) ccd += f.ccd_calls;
  EXPECT_GT(ccd, 0);
  }
}

TEST(SceneRun, ACubeOnATiltedGroundSlidesOrSticksByItsFriction) {
  // A cube of tets resting just above the ground under gravity tilted by θ (tan θ = 1/2) along x (a slope),
  // for 1 s: without friction it slides g sin θ t²/2 = 2.19; with μ = 0.2 the Coulomb law's
  // g (sin θ − μ cos θ) t²/2 = 1.31; with μ = 0.8 > tan θ it stays, but for its shear under the load.
  const double theta = std::atan(0.5);
  const auto slid = [&](const std::string& friction) {
    const SceneResult r = run_json(fmt::format(R"({{
      "mesh": {{"box": {{"element": "tet", "res": 2}}}}, "material": {{"youngs": 5e5, "poisson": 0.3}}, "density": 100,
      "gravity": [{}, {}, 0], "dt": 0.01, "end_time": 1, "frames": 4,
      "contact": {{"dhat": 0.02, "stiffness": 1e8{}}},
      "colliders": [{{"type": "plane", "point": [0, -1.01, 0], "normal": [0, 1, 0]}}]}})",
                                               9.8 * std::sin(theta), -9.8 * std::cos(theta), friction),
                                   "slide");
    EXPECT_TRUE(r.all_converged) << friction << ": " << r.failure;
    const Eigen::Index n = r.final_positions.size() / 3;
    return r.final_positions(Eigen::seqN(0, n, 3)).mean();  // the centroid's x (0 at the start)
  };
  const double none = slid(""), some = slid(R"(, "friction": 0.2)"), much = slid(R"(, "friction": 0.8)");
  std::cout << "slid " << none << " (frictionless), " << some << " (μ 0.2), " << much << " (μ 0.8)\n";
  EXPECT_NEAR(none, 9.8 * std::sin(theta) / 2.0, 0.1);
  EXPECT_NEAR(some, 9.8 * (std::sin(theta) - 0.2 * std::cos(theta)) / 2.0, 0.1);
  EXPECT_LT(std::abs(much), 0.02);
}

TEST(SceneRun, AStopKeepsTheCompletedFrames) {
  Scene s = parse_scene(json::parse(R"({"mesh": {"box": {"res": 2}}, "gravity": [0, -9.8, 0], "frames": 10, "end_time": 1,
                                        "pins": [{"region": {"min": [-1, 1, -1], "max": [1, 1, 1]}}]})"),
                        "stop.json");
  int calls = 0;
  s.solver.newton.on_iteration = [&](int, double) {
    if (++calls == 40) request_stop(SIGINT);
  };
  s.output.dir = std::filesystem::temp_directory_path() / ("snh_test_scene_stop_" + std::to_string(::getpid()));
  std::filesystem::remove_all(s.output.dir);
  std::ostringstream log;
  const SceneResult r = run_scene(s, log);
  request_stop(0);
  EXPECT_EQ(r.interrupted_by, SIGINT);
  EXPECT_FALSE(r.all_converged);
  const std::size_t frames = r.frames.size();  // frame 0 and the completed ones
  ASSERT_GT(frames, 1u);
  ASSERT_LT(frames, 11u);
  EXPECT_TRUE(std::filesystem::exists(s.output.dir / fmt::format("{:03d}.obj", frames - 1)));
  EXPECT_FALSE(std::filesystem::exists(s.output.dir / fmt::format("{:03d}.obj", frames)));
  EXPECT_TRUE(r.final_positions.allFinite());
  EXPECT_NE(r.failure.find("interrupted by signal 2"), std::string::npos) << r.failure;
  std::filesystem::remove_all(s.output.dir);
}

/// Runs `s` until its Newton iteration `stop_at`, where it gets SIGINT, then the same scene again with
/// --resume into the same directory: the two results, the interrupted run's first.
std::pair<SceneResult, SceneResult> interrupt_and_resume(Scene s, int stop_at, std::ostream& log) {
  Scene again = s;
  again.run.resume = true;
  int calls = 0;
  s.solver.newton.on_iteration = [&](int, double) {
    if (++calls == stop_at) request_stop(SIGINT);
  };
  SceneResult cut = run_scene(s, log);
  request_stop(0);
  return {std::move(cut), run_scene(again, log)};
}

struct ResumeRuns {
  SceneResult whole, cut, resumed;
};

/// Scene j (named `name`) run whole into base/full, and into base/cut interrupted at Newton iteration `stop_at`
/// and resumed there (interrupt_and_resume).
ResumeRuns whole_and_resumed(const json& j, const std::string& name, const std::filesystem::path& base, int stop_at,
                             std::ostream& log) {
  Scene full = parse_scene(j, name), cut = full;
  full.output.dir = base / "full";
  cut.output.dir = base / "cut";
  ResumeRuns r;
  r.whole = run_scene(full, log);
  std::tie(r.cut, r.resumed) = interrupt_and_resume(cut, stop_at, log);
  return r;
}

TEST(SceneRun, ResumeContinuesFromTheLastCompletedFrame) {
  // Backward Euler, BDF2 (whose checkpoint holds the step before) and TR-BDF2, with a starting velocity.
  for (const char* integrator : {"backward_euler", "bdf2", "tr_bdf2"}) {
  SCOPED_TRACE(integrator);
  json j = json::parse(R"({"mesh": {"box": {"res": 2}}, "gravity": [0, -9.8, 0], "frames": 12, "end_time": 1.2,
                           "damping": {"mass": 0.5}, "pins": [{"region": {"min": [-1, 1, -1], "max": [1, 1, 1]}}],
                           "initial": [{"type": "velocity", "value": [0.5, 0, 0], "region": {"min": [-1, -1, -1], "max": [1, 0, 1]}}]})");
  j["integrator"] = integrator;
  const auto base = std::filesystem::temp_directory_path() / ("snh_test_scene_resume_" + std::to_string(::getpid()));
  std::ostringstream log;
  const auto [a, b, c] = whole_and_resumed(j, "resume.json", base, 50, log);
  ASSERT_TRUE(a.all_converged);
  ASSERT_EQ(b.interrupted_by, SIGINT);
  ASSERT_LT(b.frames.size(), 13u);
  ASSERT_TRUE(c.all_converged) << c.failure;
  ASSERT_EQ(c.frames.size(), 13u);
  EXPECT_EQ(c.frames[1].newton_iterations, a.frames[1].newton_iterations) << "the history before the stop is kept";
  EXPECT_LT((c.final_positions - a.final_positions).cwiseAbs().maxCoeff(), 1e-6) << "the uninterrupted run's answer";
  EXPECT_NEAR(c.frames.back().kinetic_energy, a.frames.back().kinetic_energy, 1e-6);
  // Another scene in the same directory cannot resume there.
  Scene other = parse_scene(json::parse(R"({"mesh": {"box": {"res": 2}}, "frames": 12})"), "resume.json");
  other.output.dir = base / "cut";
  other.run.resume = true;
  EXPECT_THROW((void)run_scene(other, log), std::invalid_argument);
  std::filesystem::remove_all(base);
  }
}

TEST(SceneRun, ATrBdf2RunWithFrictionResumesAsItRan) {
  // TR-BDF2's first stage needs the friction force at the step's start: it is taken from the step's own
  // state (x_n and v_n), not from the friction data of the solve before, which a resumed run does not have.
  const json j = json::parse(R"({"mesh": {"box": {"res": 2, "min": [-0.1, 0.001, -0.1], "max": [0.1, 0.201, 0.1]}},
      "material": {"youngs": 1e5, "poisson": 0.45}, "density": 1000, "integrator": "tr_bdf2", "gravity": [0, -9.81, 0],
      "frames": 10, "end_time": 0.2, "contact": {"dhat": 0.002, "friction": 0.5},
      "colliders": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0]}],
      "initial": [{"type": "velocity", "value": [2, 0, 0]}], "output": {"vtu": false}})");
  const auto base = std::filesystem::temp_directory_path() / ("snh_test_scene_resume_friction_" + std::to_string(::getpid()));
  std::ostringstream log;
  const auto [a, b, c] = whole_and_resumed(j, "slide.json", base, 120, log);
  ASSERT_TRUE(a.all_converged) << a.failure;
  EXPECT_LT(a.frames.back().kinetic_energy, 0.6 * a.frames[1].kinetic_energy) << "friction slows the sliding box";
  ASSERT_EQ(b.interrupted_by, SIGINT);
  ASSERT_LT(b.frames.size(), 11u);
  ASSERT_GT(b.frames.size(), 2u) << "the run stopped after a frame or two, so the resumed run has a friction state to lack";
  ASSERT_TRUE(c.all_converged) << c.failure;
  ASSERT_EQ(c.frames.size(), 11u);
  EXPECT_LT((c.final_positions - a.final_positions).cwiseAbs().maxCoeff(), 1e-6) << "the uninterrupted run's answer";
  std::filesystem::remove_all(base);
}

TEST(SceneRun, KeepGoingWritesFramesThatDoNotConvergeMarkedAndGoesOn) {
  // One Newton iteration a frame (and no step retried in halves) is not enough for a box falling from its pins' hold: every frame fails.
  const json j = json::parse(R"({"mesh": {"box": {"res": 2}}, "gravity": [0, -9.8, 0], "frames": 6, "end_time": 0.6,
                                 "solver": {"max_iterations": 1, "step_halvings": 0}, "pins": [{"region": {"min": [-1, 1, -1], "max": [1, 1, 1]}}]})");
  const auto base = std::filesystem::temp_directory_path() / ("snh_test_scene_keep_going_" + std::to_string(::getpid()));
  std::ostringstream log;
  Scene stop = parse_scene(j, "keep.json");
  stop.output.dir = base / "stop";
  const SceneResult a = run_scene(stop, log);
  EXPECT_FALSE(a.all_converged);
  EXPECT_EQ(a.frames.size(), 2u) << "without keep_going the run stops at the first frame that fails";
  EXPECT_EQ(a.unconverged, std::vector<int>{1});

  Scene going = parse_scene(j, "keep.json");
  going.output.dir = base / "going";
  going.run.keep_going = true;
  std::ostringstream going_log;
  const SceneResult b = run_scene(going, going_log);
  EXPECT_FALSE(b.all_converged);
  ASSERT_EQ(b.frames.size(), 7u) << going_log.str();
  EXPECT_EQ(b.unconverged, (std::vector<int>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(b.failure.rfind("frame 1, ", 0), 0u) << b.failure;
  EXPECT_TRUE(std::filesystem::exists(going.output.dir / "006.obj"));
  EXPECT_NE(going_log.str().find("NOT CONVERGED"), std::string::npos);
  EXPECT_NE(going_log.str().find("FINISHED WITH 6 FRAMES NOT CONVERGED"), std::string::npos) << going_log.str();
  std::ifstream in(going.output.dir / "stats.json");
  const json stats = json::parse(in);
  EXPECT_EQ(stats["all_converged"], false);
  EXPECT_EQ(stats["unconverged_frames"], json::array({1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(stats["frames"][6]["converged"], false);

  // Interrupted in frame 4 and resumed: the frames before the stop stay marked, and the answer is the same.
  Scene cut = parse_scene(j, "keep.json");
  cut.output.dir = base / "cut";
  cut.run.keep_going = true;
  const auto [c, d] = interrupt_and_resume(cut, 4, log);
  ASSERT_EQ(c.interrupted_by, SIGINT);
  EXPECT_EQ(d.unconverged, b.unconverged);
  EXPECT_FALSE(d.all_converged);
  EXPECT_LT((d.final_positions - b.final_positions).cwiseAbs().maxCoeff(), 1e-9);  // to rounding (the box is 2 wide)
  std::filesystem::remove_all(base);
}

TEST(SceneRun, AMeshFileRelativeToTheScene) {
  const auto dir = std::filesystem::temp_directory_path() / ("snh_test_scene_file_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "meshes");
  std::ofstream(dir / "meshes" / "two.node") << "5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n";
  std::ofstream(dir / "meshes" / "two.ele") << "2 4 0\n1 1 2 3 4\n2 2 4 3 5\n";  // the second inverted
  const Scene s = parse_scene(json::parse(R"({"mesh": {"file": "meshes/two.ele"}, "pins": [{"indices": [0, 1, 2]}],
                                             "gravity": [0, 0, -1], "frames": 2, "end_time": 0.1})"),
                              dir / "s.json");
  EXPECT_EQ(s.mesh.file, dir / "meshes" / "two.ele");
  const std::shared_ptr<const SceneBody> m = scene_body(s);
  EXPECT_EQ(m->mesh.cell_count(), 2);
  EXPECT_EQ(m->reoriented, 1);
  Scene run = s;
  run.output.dir = dir / "out";
  std::ostringstream log;
  const SceneResult r = run_scene(run, log);
  EXPECT_TRUE(r.all_converged) << r.failure;
  EXPECT_EQ(r.element, CellType::tet4);
  EXPECT_NE(log.str().find("1 inverted cell(s) re-oriented"), std::string::npos) << log.str();
  EXPECT_EQ(r.warnings, std::vector<std::string>{"1 inverted cell(s) of the mesh re-oriented"});  // snh.run_scene's "warnings"
  // A broken mesh file: its reader's one-line error, naming the file and line.
  std::ofstream(dir / "meshes" / "two.ele") << "2 4 0\n1 1 2 3 4\n";
  try {
    (void)build_scene(parse_scene(json::parse(R"({"mesh": {"file": "meshes/two.ele"}})"), dir / "s.json"));
    ADD_FAILURE() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("two.ele:3: the file ends"), std::string::npos) << e.what();
  }
  EXPECT_EQ(error_of(json::parse(R"({"mesh": {"file": "x.msh", "box": {}}})")), "s.json: mesh: give exactly one of box or file");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace snh
