#pragma once
// Checkpoints for --resume (docs/design.md): after every completed step a run writes checkpoint.bin
// (atomically) with the exact state needed to continue: the step, the positions and one auxiliary vector
// (the previous solution, or the last two, for extrapolation; or the velocity, and for BDF2 the previous positions,
// velocity and step length), and a fingerprint of the settings that
// determine the result, so that a resume with other settings is refused.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace snh {

struct Checkpoint {
  std::string fingerprint;
  int step = 0;
  double time = 0.0;
  Eigen::VectorXd x, aux;
};

/// Writes DIR/checkpoint.bin atomically.
void write_checkpoint(const std::filesystem::path& dir, const Checkpoint& c);
/// Reads DIR/checkpoint.bin; nullopt if there is none. Throws std::runtime_error (one line) if it is
/// damaged.
[[nodiscard]] std::optional<Checkpoint> read_checkpoint(const std::filesystem::path& dir);
/// Reads the checkpoint for a resume and checks it: present, the same fingerprint (else an error naming
/// both), and vectors of `dofs` entries. Throws std::invalid_argument with a one-line message.
[[nodiscard]] Checkpoint checkpoint_for_resume(const std::filesystem::path& dir, const std::string& fingerprint,
                                               Eigen::Index dofs);

/// The first `count` entries of the array `key` ("steps", "frames") in DIR/stats.json: the history of the
/// run being resumed. Throws std::invalid_argument (one line) if the file is missing, is not JSON, or lists
/// fewer entries.
[[nodiscard]] std::vector<nlohmann::json> history_for_resume(const std::filesystem::path& dir, const char* key, int count);

}  // namespace snh
