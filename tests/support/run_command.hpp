// SPDX-License-Identifier: MIT
// Runs a shell command as a user would, outside this test's MPI job (a clean environment), and
// captures its exit code and combined output.
#pragma once
#include <string>

namespace tessera::test {

struct CommandResult {
  int code;
  std::string output;
};

CommandResult run_shell(const std::string& script);

}  // namespace tessera::test
