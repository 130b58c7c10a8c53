// ReadAhead and WriteBehind (tools/cli/pipeline.h): order, the bound on items in flight, and
// failures handed back to the caller in order, without deadlock or std::terminate.
#include "cli/pipeline.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

using namespace range_nlm::tools;

namespace
{
void
pause(int ms)
{
  std::this_thread::sleep_for(std::chrono::milliseconds(ms));
}
} // namespace

TEST(ReadAhead, DeliversEveryItemInOrderAndNeverMoreThanOneAhead)
{
  // taken: items handed out so far; started: the last item the reader began. While the caller
  // holds item i, the reader must get to item i + 1 (it reads ahead) and not to i + 2.
  std::atomic<int> taken{0}, started{-1}, furthest_ahead{0};
  ReadAhead<int> reader(20, [&](std::size_t i) {
    started = static_cast<int>(i);
    furthest_ahead = std::max<int>(furthest_ahead, static_cast<int>(i) - taken);
    return static_cast<int>(i) * 10;
  });
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(reader.next(), i * 10);
    taken = i + 1;
    if (i + 1 < 20) {
      // However slow the machine (sanitizers, load), the reader starts the next item on its own.
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
      while (started < i + 1 && std::chrono::steady_clock::now() < deadline)
        pause(1);
      EXPECT_EQ(started, i + 1) << "the reader did not read item " << i + 1 << " ahead";
    }
    pause(2); // time for the reader to run further ahead, were it allowed to
    EXPECT_LE(started, i + 1);
  }
  EXPECT_LE(furthest_ahead, 1);
}

TEST(ReadAhead, ThrowsEachFailureWithItsItemAndGoesOn)
{
  ReadAhead<std::string> reader(4, [](std::size_t i) -> std::string {
    if (i == 1)
      throw std::invalid_argument("item 1 is bad");
    if (i == 2)
      throw std::runtime_error("item 2 is bad too");
    return "item " + std::to_string(i);
  });
  EXPECT_EQ(reader.next(), "item 0");
  EXPECT_THROW(
      try { reader.next(); } catch (const std::invalid_argument& e) {
        EXPECT_STREQ(e.what(), "item 1 is bad");
        throw;
      },
      std::invalid_argument);
  EXPECT_THROW(reader.next(), std::runtime_error);
  EXPECT_EQ(reader.next(), "item 3");
}

TEST(ReadAhead, StopsWhenDestroyedBeforeTheEnd)
{
  std::atomic<int> produced{0};
  {
    ReadAhead<int> reader(1000, [&](std::size_t i) {
      ++produced;
      pause(1);
      return static_cast<int>(i);
    });
    EXPECT_EQ(reader.next(), 0);
  } // joins without hanging
  EXPECT_LE(produced, 3);
}

TEST(WriteBehind, RunsTasksInOrderWithOneFrameInFlight)
{
  std::vector<int> order;
  std::atomic<int> frames{0}, most_frames{0};
  WriteBehind writer;
  for (int i = 0; i < 30; ++i) {
    const bool frame = i % 3 != 0;
    writer.post(
        [&, i, frame] {
          if (frame)
            most_frames = std::max<int>(most_frames, ++frames);
          pause(1);
          order.push_back(i);
          if (frame)
            --frames;
        },
        frame);
  }
  writer.drain();
  ASSERT_EQ(order.size(), 30u);
  for (int i = 0; i < 30; ++i)
    EXPECT_EQ(order[i], i);
  EXPECT_EQ(most_frames, 1);
}

TEST(WriteBehind, FirstFailureStopsLaterTasksAndIsThrownToTheCaller)
{
  std::vector<int> ran;
  WriteBehind writer;
  writer.post([&] { ran.push_back(0); }, true);
  writer.post([&] { throw std::runtime_error("cannot write frame 1"); }, true);
  // Posting goes on until the failure is seen; nothing posted after it runs.
  bool thrown = false;
  for (int i = 2; i < 100 && !thrown; ++i) {
    try {
      writer.post([&, i] { ran.push_back(i); }, true);
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "cannot write frame 1");
      thrown = true;
    }
  }
  EXPECT_TRUE(thrown);
  EXPECT_THROW(writer.drain(), std::runtime_error);
  EXPECT_EQ(ran, std::vector<int>{0});
}

TEST(WriteBehind, DestroyedWithoutDrainRunsWhatWasPosted)
{
  std::atomic<int> ran{0};
  {
    WriteBehind writer;
    for (int i = 0; i < 10; ++i)
      writer.post(
          [&] {
            pause(1);
            ++ran;
          },
          i % 2 == 0);
  }
  EXPECT_EQ(ran, 10);
}
