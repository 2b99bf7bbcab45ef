#pragma once
// What a flesh scene adds to a volume scene (scene_build.hpp, scene_run.hpp): its defaults at the flesh's
// scale (the clip's length and frames, Newton's tolerances, contact's d̂ and κ), its terms (the bones'
// kinematic set is scene_kinematics'; here the soft binding, the carrier that predicts with the bones, the
// bones' capsules against the skin), and its output (its settings and header, the render surface's volumes per
// frame, surface/ and lbs/ frames, flesh.usda and bones.json).
#include <vector>

#include "snh/run/driver.hpp"
#include "snh/setup/scene_build.hpp"

namespace snh {

/// The end time and frames where the scene gives none: the clip's length (when it has one), and frames on the
/// grid of 1 / fps from 0, up to the end time rounded up to a whole frame (which becomes the end time).
/// Throws SceneError when that makes more than TimeSpec::max_frames.
void flesh_time(const Scene& scene, const Flesh& flesh, double& end_time, int& frames);
/// Newton iterations a flesh frame may take unless the scene's solver says: more than the paper programs' 50,
/// for a joint bent far crushes cells that Newton then needs many iterations to settle (assimp's BCN_Epileptic
/// needs up to 166 at its hip's deepest bend).
inline constexpr int kFleshNewtonIterations = 200;
/// Newton's stopping rule at the flesh's scale, unless the scene sets one: a force of 1e-6 of what a unit
/// strain puts on a cell's face (E h², h the cell size), and the step rule derived from it through the
/// stiffness the solve sees, (λ + 2μ) h: a Newton step under tolerance / ((λ + 2μ) h), the displacement that
/// such a force moves a cell's vertex by (docs/solvers.md, "When a solve has converged"); at most
/// kFleshNewtonIterations iterations.
[[nodiscard]] NewtonOptions flesh_newton_options(const SolverSpec& solver, const Flesh& flesh, const Lame& lame);
/// Contact's d̂ and κ, as given or the flesh's defaults (flesh_contact_dhat, flesh_contact_stiffness).
[[nodiscard]] ContactParameters flesh_contact(const ContactSpec& contact, const Flesh& flesh, double youngs);
/// A flesh scene's own terms: the carrier (quasi-static), the soft binding's springs into setup.terms, and the
/// bones' capsule colliders into `bones` (contact.bones) for contact_terms to place among the contact terms.
void add_flesh_terms(const BuiltScene& built, SimulationSetup& setup, std::vector<std::shared_ptr<Term>>& bones);
/// A flesh run's own output (see the header) added to its plan.
void add_flesh_output(const BuiltScene& built, const Simulation& sim, RunPlan& plan);

}  // namespace snh
