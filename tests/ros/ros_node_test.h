// A test program as a ROS node beside the processes it starts: the master and this process's node
// (a gtest environment), messages received on a topic, and waits on what the master lists.
#pragma once

#include "ros_test_support.h"

#include <gtest/gtest.h>
#include <ros/ros.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

namespace range_nlm
{
namespace test
{

/// The master of the test program (RosEnvironment starts it before the tests).
inline RosMaster* g_master = nullptr;

/// The master for the whole test program, and this process as a ROS node.
class RosEnvironment : public ::testing::Environment
{
public:
  RosEnvironment(int argc, char** argv, std::string node_name = "range_nlm_test")
    : argc_(argc), argv_(argv), node_name_(std::move(node_name))
  {
  }
  void SetUp() override
  {
    g_master = new RosMaster();
    ros::init(argc_, argv_, node_name_, ros::init_options::AnonymousName | ros::init_options::NoSigintHandler);
    ASSERT_TRUE(ros::master::check()) << "no master at " << g_master->uri();
    spinner_ = std::make_unique<ros::AsyncSpinner>(2);
    spinner_->start();
  }
  void TearDown() override
  {
    if (spinner_)
      spinner_->stop();
    ros::shutdown();
    delete g_master; // stops rosmaster
    g_master = nullptr;
  }

private:
  int argc_;
  char** argv_;
  std::string node_name_;
  std::unique_ptr<ros::AsyncSpinner> spinner_;
};

/// Messages received on a topic, in order.
template <typename Message>
class Inbox
{
public:
  explicit Inbox(const std::string& topic)
  {
    ros::NodeHandle node;
    subscriber_ = node.subscribe<Message>(topic, 50, [this](const typename Message::ConstPtr& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      messages_.push_back(m);
      arrived_.notify_all();
    });
  }
  /// The next message, or null after `seconds`.
  typename Message::ConstPtr next(double seconds = 30.0)
  {
    std::unique_lock<std::mutex> lock(mutex_);
    arrived_.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return !messages_.empty(); });
    if (messages_.empty())
      return nullptr;
    auto m = messages_.front();
    messages_.pop_front();
    return m;
  }
  std::size_t pending()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return messages_.size();
  }
  std::uint32_t publishers() const { return subscriber_.getNumPublishers(); }

private:
  ros::Subscriber subscriber_;
  std::mutex mutex_;
  std::condition_variable arrived_;
  std::deque<typename Message::ConstPtr> messages_;
};

/// Waits until `done` holds (true) or 60 s pass (false). Generous: on a loaded machine a nodelet
/// manager has taken more than 20 s to load the plugin and connect; no caller waits for something
/// that must not happen, so a passing test never waits this long.
template <typename Condition>
bool
waitFor(const Condition& done)
{
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline)
      return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

/// The master lists `topic` as published.
inline bool
advertised(const std::string& topic)
{
  ros::master::V_TopicInfo topics;
  ros::master::getTopics(topics);
  for (const auto& t : topics)
    if (t.name == topic)
      return true;
  return false;
}

/// The whole text of a child's log file.
inline std::string
readLog(const std::string& path)
{
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

} // namespace test
} // namespace range_nlm
