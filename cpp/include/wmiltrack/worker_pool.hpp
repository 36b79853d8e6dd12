// Work spread over the core's threads: several targets' frame steps (or searches, or learning
// steps) at once. The threads stay between calls (starting one costs more than a small job),
// one pool per process; worker_pool.cpp says how they wait.
#pragma once

#include <functional>

namespace wmiltrack {

// fn(i) for every i in [0, n), spread over up to `threads` threads (the calling one among
// them; jobs are handed out one at a time, in order). The first exception a job throws is
// rethrown once every thread has finished; the other jobs still run.
void parallel_for(int n, int threads, const std::function<void(int)>& fn);

}  // namespace wmiltrack
