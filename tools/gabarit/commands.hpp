// The gabarit CLI's subcommands; each takes the arguments after its name and
// returns the process exit code (errors are thrown as app::Error/UsageError).
#pragma once

#include <string>
#include <vector>

namespace gabarit::cli {

int tables_build(const std::vector<std::string>& args);
int tables_inspect(const std::vector<std::string>& args);
int tables_analyse(const std::vector<std::string>& args);
int tables_export_hdl(const std::vector<std::string>& args);
int synth(const std::vector<std::string>& args);
int detect(const std::vector<std::string>& args);
int track(const std::vector<std::string>& args);
int eval(const std::vector<std::string>& args);
int vectors(const std::vector<std::string>& args);
int hil(const std::vector<std::string>& args);
// gabarit hil lava-job | lava-replay (cmd_hil_lava.cpp)
int hil_lava(const std::string& verb, const std::vector<std::string>& args);

}  // namespace gabarit::cli
