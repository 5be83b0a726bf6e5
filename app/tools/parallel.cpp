#include "tools/parallel.h"

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace skyloc::tools {

int DefaultJobs() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

void ParallelFor(int jobs, int tasks, const std::function<void(int task, int worker)>& fn) {
  const int workers = std::clamp(jobs, 1, std::max(1, tasks));
  std::atomic<int> next{0};
  const auto work = [&](int worker) {
    for (int task = next.fetch_add(1); task < tasks; task = next.fetch_add(1))
      fn(task, worker);
  };
  std::vector<std::thread> threads;
  threads.reserve(static_cast<std::size_t>(workers - 1));
  for (int w = 1; w < workers; ++w)
    threads.emplace_back(work, w);
  work(0);
  for (std::thread& t : threads)
    t.join();
}

namespace {

// A worker's own buffer of N floats, sized on the worker's first task.
std::vector<float>& WorkerBuffer(std::vector<std::vector<float>>* buffers, int worker,
                                 std::size_t n) {
  std::vector<float>& b = (*buffers)[static_cast<std::size_t>(worker)];
  if (b.empty())
    b.resize(n);
  return b;
}

}  // namespace

void RunBlockedSeqSlam(dsp::BlockedSeqSlam& engine, int jobs,
                       const std::function<void(int)>& progress) {
  const int workers = std::max(1, jobs);
  std::vector<std::vector<float>> scratch(static_cast<std::size_t>(workers));
  std::vector<std::vector<float>> scores(static_cast<std::size_t>(workers));
  constexpr int kGroup = dsp::BlockedSeqSlam::kColumnGroup;
  // Frames per search task: each search is O(n_ref x velocities x ds), a few per task.
  constexpr int kFrames = 4;
  for (int b = 0; b < engine.block_count(); ++b) {
    engine.Begin(b);
    const int columns = engine.ColumnCount();
    ParallelFor(workers, (columns + kGroup - 1) / kGroup, [&](int task, int worker) {
      engine.ComputeColumns(task * kGroup, std::min(columns, (task + 1) * kGroup),
                            WorkerBuffer(&scratch, worker, engine.ScratchFloats()));
    });
    const int frames = engine.SearchCount();
    ParallelFor(workers, (frames + kFrames - 1) / kFrames, [&](int task, int worker) {
      engine.Search(task * kFrames, std::min(frames, (task + 1) * kFrames),
                    WorkerBuffer(&scores, worker, engine.ScoreFloats()));
    });
    if (progress)
      progress(std::min(engine.n_query(), (b + 1) * engine.block_columns()));
  }
}

}  // namespace skyloc::tools
