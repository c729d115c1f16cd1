// gabarit eval
#include <iostream>

#include "gabarit/app/args.hpp"
#include "commands.hpp"
#include "gabarit/app/evaluation.hpp"

namespace gabarit::cli {

int eval(const std::vector<std::string>& argv) {
  app::Args args("eval", "--poses POSES.csv --gt gt.csv [--require-exact]",
            "Compares tracked poses with ground truth and prints accuracy as JSON: frames on the exact pixel,\n"
            "within 1 and 2 px, mean and max error, and the wrongly tracked frames.",
            {{"--poses", "POSES.csv", "output of gabarit track", false, true},
             {"--gt", "gt.csv", "ground truth from gabarit synth", false, true},
             {"--require-exact", "", "exit 1 unless every visible frame is on the exact pixel"}});
  if (!args.parse(argv)) return 0;
  const auto a = app::evaluate(app::read_pose_csv(args.get("--poses")), app::read_pose_csv(args.get("--gt")));
  std::cout << app::accuracy_json(a);
  if (args.has("--require-exact") && (a.exact != a.frames || a.missing != 0 || a.frames == 0)) return 1;
  return 0;
}

}  // namespace gabarit::cli
