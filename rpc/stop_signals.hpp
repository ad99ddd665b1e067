// The stop signals of demcal's processes (server, worker, the embedded default): SIGINT and SIGTERM
// are blocked in every thread and taken synchronously with sigwait by one of them.
#pragma once

#include <pthread.h>

#include <csignal>

namespace demcal::rpc {

/// Blocks SIGINT and SIGTERM in the calling thread, so in every thread it starts afterwards, and
/// returns their set for sigwait. Call it before the process starts its other threads.
inline sigset_t block_stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  return set;
}

}  // namespace demcal::rpc
