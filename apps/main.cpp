// comorph: co-optimization of morphology and behaviour of a modular robot.
#include <spdlog/spdlog.h>

#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <exception>
#include <iostream>

#include "command_registry.hpp"
#include "common/file_io.hpp"
#include "common/heap.hpp"

int main(int argc, char** argv) {
  comorph::keep_freed_memory_for_reuse();  // before the first allocation of note
  CLI::App app{"comorph: co-optimize the configuration and the motion of a chain-type "
               "modular robot with hierarchical deep RL"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "comorph 0.1.0");
  for (const auto& setup : comorph::cli::command_setups()) setup(app);
  // Under a file-size limit (ulimit -f) a write then fails with "File too
  // large" and is reported like a full disk, instead of killing the process.
  std::signal(SIGXFSZ, SIG_IGN);
  // Output to a file or pipe is written once, at the end, for outputs up to
  // 1 MiB: a failed write then still has its errno when flush_stdout() checks
  // (after a failure mid-way, std::cout stops writing and the reason is lost).
  static char stdout_buffer[1 << 20];
  if (!::isatty(STDOUT_FILENO)) std::setvbuf(stdout, stdout_buffer, _IOFBF, sizeof(stdout_buffer));
  try {
    app.parse(argc, argv);
    // `comorph export-mjcf > /dev/full` must not exit 0.
    comorph::flush_stdout();
  } catch (const CLI::ParseError& e) {
    // --help and --version are "errors" with code 0; every real parse error is status 2.
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    std::cerr << "comorph: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
