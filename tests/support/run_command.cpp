// SPDX-License-Identifier: MIT
#include "support/run_command.hpp"

#include <sys/wait.h>

#include <array>
#include <cstdio>

namespace tessera::test {

CommandResult run_shell(const std::string& script) {
  // env -i: the child must not inherit this test's MPI job (it would try to join it).
  std::string quoted;
  for (const char c : script) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  const std::string cmd =
      "env -i PATH=/usr/bin:/bin OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 sh -c '" + quoted + "' 2>&1";
  CommandResult r{0, ""};
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 512> buf{};
  while (fgets(buf.data(), buf.size(), p)) r.output += buf.data();
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace tessera::test
