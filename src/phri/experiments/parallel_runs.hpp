#pragma once
// Independent simulated runs on several threads: run_in_parallel(count, jobs, task) calls
// task(i) once for every i in [0, count), on at most `jobs` threads (the calling one included),
// each index taken by the next free thread. The first exception a task throws stops the others
// from starting new indices and is rethrown once every thread has finished. Each task owns its
// plant and controller; what they share (loaded models, options) must be read-only.
// (safety_fuzz.cpp keeps its own pool, which also orders tasks by cost and counts findings.)
#include <functional>

namespace phri {

void run_in_parallel(int count, int jobs, const std::function<void(int)>& task);

}  // namespace phri
