// The thesis's section 6.4 comparison on the suite (issue 31, item 4): per
// method, Fig. 6.60's error buckets pooled over a half's scenes and Fig.
// 6.61's time per frame with the searching (re-acquisition, detection)
// frames split out, then issue 31's targets for the particle filter scene by
// scene.
#pragma once

#include <sstream>
#include <string>
#include <vector>

#include "suite_results.hpp"

namespace gabarit::bench {

void section64_table(const std::vector<SceneResult>& scenes, const std::string& title, std::ostringstream& md);

}  // namespace gabarit::bench
