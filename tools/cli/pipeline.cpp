#include "cli/pipeline.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace range_nlm
{
namespace tools
{

int
defaultThreads()
{
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

void
useThreads(int threads)
{
#ifdef _OPENMP
  if (threads > 0)
    omp_set_num_threads(threads);
#else
  (void)threads;
#endif
}

WriteBehind::WriteBehind()
    : thread_([this, threads = defaultThreads()] {
        useThreads(threads);
        work();
      })
{
}

WriteBehind::~WriteBehind()
{
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable())
    thread_.join();
}

void
WriteBehind::post(std::function<void()> task, bool holds_frame)
{
  std::unique_lock<std::mutex> lock(mutex_);
  wake_.wait(lock, [&] { return error_ || ((!holds_frame || frames_ == 0) && queue_.size() < kMaxQueued); });
  if (error_)
    std::rethrow_exception(error_);
  queue_.push_back(Task{std::move(task), holds_frame});
  frames_ += holds_frame;
  lock.unlock();
  wake_.notify_all();
}

void
WriteBehind::drain()
{
  std::unique_lock<std::mutex> lock(mutex_);
  wake_.wait(lock, [&] { return error_ || (queue_.empty() && !running_); });
  if (error_)
    std::rethrow_exception(error_);
}

void
WriteBehind::work()
{
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [&] { return stop_ || !queue_.empty(); });
    if (queue_.empty() || error_)
      return; // stopped, with nothing left to run (or nothing that may run after a failure)
    Task task = std::move(queue_.front());
    queue_.pop_front();
    running_ = true;
    lock.unlock();
    std::exception_ptr error;
    try {
      task.run();
    } catch (...) {
      error = std::current_exception();
    }
    task.run = nullptr; // the frame it held is released before the next one may be posted
    lock.lock();
    running_ = false;
    frames_ -= task.holds_frame;
    if (error) {
      error_ = error;
      queue_.clear();
      frames_ = 0;
    }
    wake_.notify_all();
  }
}

} // namespace tools
} // namespace range_nlm
