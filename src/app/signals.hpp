// SPDX-License-Identifier: MIT
// SIGTERM / SIGUSR1 ask the run to checkpoint and stop. A signal handler can only set a flag of
// static storage; this flag is the one piece of process-wide state in Tessera.
#pragma once
#include <csignal>

namespace tessera {

void install_stop_signal_handlers();
bool stop_requested();

}  // namespace tessera
