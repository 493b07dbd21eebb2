// Checked writes of LibTorch archives (learner checkpoints, the scene
// classifier's weights). Its own library (comorph_common_torch): the rest of
// common does not link torch.
#pragma once

#include <string>

namespace torch::serialize {
class OutputArchive;
}  // namespace torch::serialize

namespace comorph {

// Writes an archive to `path`, checked: a failed write (full disk) throws
// "cannot write <path>: <reason>" once the archive is done. LibTorch 1.13
// must never see the failure itself: its zip writer then throws again from a
// destructor, and the process aborts (std::terminate, exit 134).
void save_archive(torch::serialize::OutputArchive& archive, const std::string& path);

}  // namespace comorph
