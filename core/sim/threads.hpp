#pragma once
// How the simulation's OpenMP threads wait for each other.

namespace demcal::sim {

/// Makes the process's OpenMP threads wait passively at barriers (OMP_WAIT_POLICY=passive)
/// unless the environment already sets OMP_WAIT_POLICY. GOMP reads the policy once, when the
/// library loads, so the program is executed again with the variable set; call it first thing
/// in main. With GOMP's default (spinning), a thread waiting at a barrier holds a core the
/// thread it waits for may need: on a shared 2-core machine a 1,000-particle bed on 2 threads
/// took 14x the time of 1 thread (docs/engine.md, "Threads"). If the program cannot be executed
/// again it goes on with the default policy.
void wait_passively(char** argv);

}  // namespace demcal::sim
