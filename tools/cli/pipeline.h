// Overlapping a tool's reading and writing of frames with its filtering: a reader thread that
// prepares the next frame while the current one is filtered (ReadAhead), and a writer thread that
// writes the previous result while the next one is filtered (WriteBehind). Each holds a fixed
// number of frames, whatever the length of the sequence, and hands every failure back to the
// calling thread, in order, as the exception it was.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

namespace range_nlm
{
namespace tools
{

/// The number of threads the OpenMP parallel regions the calling thread starts use when they do
/// not give one (1 without OpenMP).
int
defaultThreads();
/// Sets that number for the calling thread; `threads` <= 0 leaves it. A thread starts with the
/// number OMP_NUM_THREADS gave, whatever its parent set: the tools' threads below take their
/// parent's, so that --threads holds in every thread.
void
useThreads(int threads);

/// Produces items 0, 1, ..., count - 1 with `produce(i)` on a thread of its own, one item ahead of
/// the caller: item i + 1 is produced while the caller works on item i, never further ahead. An
/// exception of `produce(i)` is kept and thrown by the next() that returns item i, so the caller
/// sees exactly what a call of `produce(i)` in its own thread would have thrown.
template <typename T>
class ReadAhead
{
public:
  ReadAhead(std::size_t count, std::function<T(std::size_t)> produce)
      : count_(count), produce_(std::move(produce))
  {
    if (count_ > 0)
      thread_ = std::thread([this, threads = defaultThreads()] {
        useThreads(threads);
        work();
      });
  }
  /// Stops producing (an item being produced is finished first) and joins the thread.
  ~ReadAhead()
  {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable())
      thread_.join();
  }
  ReadAhead(const ReadAhead&) = delete;
  ReadAhead& operator=(const ReadAhead&) = delete;

  /// The next item, in order (waits for it); throws what producing it threw. At most `count` calls.
  T next()
  {
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait(lock, [this] { return ready_.has_value(); });
    Slot slot = std::move(*ready_);
    ready_.reset();
    lock.unlock();
    wake_.notify_all(); // the producer may start on the item after this one
    if (slot.error)
      std::rethrow_exception(slot.error);
    return std::move(slot.item);
  }

private:
  struct Slot
  {
    T item{};
    std::exception_ptr error;
  };

  void work()
  {
    for (std::size_t i = 0; i < count_; ++i) {
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [this] { return stop_ || !ready_.has_value(); });
        if (stop_)
          return;
      }
      Slot slot;
      try {
        slot.item = produce_(i);
      } catch (...) {
        slot.item = T{};
        slot.error = std::current_exception();
      }
      {
        std::lock_guard<std::mutex> lock(mutex_);
        ready_ = std::move(slot);
      }
      wake_.notify_all();
    }
  }

  const std::size_t count_;
  std::function<T(std::size_t)> produce_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::optional<Slot> ready_; // produced, not yet taken
  bool stop_ = false;
  std::thread thread_;
};

/// Runs tasks on a thread of its own, in the order they are posted, while the caller goes on.
/// A task that holds a frame (a result to write) is posted only when no other such task is queued
/// or running, so that one frame is written while the caller filters the next; light tasks
/// (messages, records) queue behind it, at most kMaxQueued of them. The first task that throws
/// ends the work: no later task runs, and its exception is thrown by the next post() or drain().
class WriteBehind
{
public:
  static constexpr std::size_t kMaxQueued = 64;

  WriteBehind();
  /// Runs the tasks still queued (unless one failed) and joins the thread; throws nothing.
  ~WriteBehind();
  WriteBehind(const WriteBehind&) = delete;
  WriteBehind& operator=(const WriteBehind&) = delete;

  /// Queues `task`; waits while a frame is in flight if `holds_frame`, or while the queue is full.
  /// Throws the exception of an earlier task that failed (and then queues nothing).
  void post(std::function<void()> task, bool holds_frame);
  /// Waits until every task posted has run; throws the exception of the first that failed.
  void drain();

private:
  struct Task
  {
    std::function<void()> run;
    bool holds_frame = false;
  };
  void work();

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Task> queue_;
  std::size_t frames_ = 0; // tasks holding a frame, queued or running
  bool running_ = false;   // a task is running
  bool stop_ = false;
  std::exception_ptr error_;
  std::thread thread_;
};

} // namespace tools
} // namespace range_nlm
