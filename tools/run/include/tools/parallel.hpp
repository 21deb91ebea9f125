// The tools' one way of running independent flights side by side (the Monte Carlo keeps its own
// pool: tools/montecarlo.hpp).
//
// Every parallel step of the diagnosis (the search's candidate models, the track initialisation's
// heading screen, the profile runs of an interval, the intervals of several findings, the
// separation trials) and of the paper's analysis (its bank-to-turn flights) is a list of
// independent jobs whose results go into their own slots in input order: the outcome is the same
// whatever the number of threads or the order they finish in.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace tools {

/// Calls job(i) for every i in [0, n) on min(hardware threads, n) threads (the caller's thread is
/// one of them) and returns when all are done. job must write only to what belongs to i, and must
/// not throw (a throw on a worker thread ends the process).
template <class Job>
void for_each_parallel(std::size_t n, Job&& job) {
  std::atomic<std::size_t> next{0};
  const auto worker = [&]() {
    for (std::size_t i = next++; i < n; i = next++) job(i);
  };
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const unsigned n_threads = static_cast<unsigned>(std::min<std::size_t>(hw, std::max<std::size_t>(1, n)));
  std::vector<std::thread> threads;
  for (unsigned t = 1; t < n_threads; ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
}

}  // namespace tools
