// umbra_server against a real ROS 1 master on the loopback interface.
//
// The test starts `roscore` on a free port of 127.0.0.1 (ROS_MASTER_URI,
// ROS_HOSTNAME, ROS_HOME pointing at its own scratch folder), starts
// umbra_server with octomap_server's parameters, and publishes scans as a
// robot would: the sensor pose on /tf, then the cloud (FLOAT64 x y z in the
// sensor frame, a row of NaN, padding) on the node's cloud_in. After each
// cloud it waits for the node's octomap_binary / octomap_full messages with
// that cloud's stamp. The last ones must hold, byte for byte, the tree of
// the map `umbra build` makes from the same scans (a bag of the same
// messages for the simulated office; the .graph file itself for the shared
// 3DTK scans) and the library makes from the simulator's points directly.
// Then ~clear_bbx must free exactly the known voxels of a box, and ~reset
// must empty the map. Depth images (16UC1 and 32FC1, with their CameraInfo,
// a color image, and TF for the camera's optical frame) must give the map
// the library's insert_depth_image makes of the same images, and malformed
// ones a log line naming the image while the node goes on. ROS's own command-line tools must work on the
// node as a user types them (rostopic echo, rosservice call, after sourcing build/ros/messages/setup.sh), and
// a cloud in a frame TF does not name must be named in a warning. Every process the test starts is stopped by
// its id at the end. Without roscore or umbra_server the test is skipped with a message.
//
// Waiting has generous limits (a hung node fails the test instead of hanging
// CI); they bound waits, they do not measure speed.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <octomap_msgs/BoundingBoxQuery.h>
#include <nav_msgs/OccupancyGrid.h>
#include <octomap_msgs/Octomap.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Empty.h>
#include <umbra_msgs/CheckCollision.h>
#include <umbra_msgs/MergeMap.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <mutex>
#include <optional>
#include <random>
#include <sstream>
#include <thread>

#include "map_messages.hpp"
#include "umbra/query/navigation_grid.hpp"
#include "ros_test_support.hpp"
#include "support/test_support.hpp"
#include "umbra/io/map_file.hpp"
#include "umbra/io/spill_file.hpp"
#include "umbra/sim/depth_camera.hpp"
#include "umbra/sim/scene.hpp"

#include <gtest/gtest.h>

namespace umbra::test {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr auto kStartLimit = std::chrono::seconds(120);
constexpr auto kMessageLimit = std::chrono::seconds(300);
/// A scan or image with neither a map nor an error after this long is sent once more (its TF too): on a
/// loaded machine one of a test's single messages has been seen to get stuck between the two nodes (the
/// node had the image, its CameraInfo and color but never matched them), where a sensor's stream would
/// simply go on with the next message. A message merely late is then inserted twice, which fails the
/// comparison with the expected map rather than passing.
constexpr auto kResendAfter = std::chrono::seconds(30);

/// A free TCP port on 127.0.0.1 (the kernel's choice; released again for roscore to take).
int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  socklen_t length = sizeof address;
  if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    if (fd >= 0) ::close(fd);
    return -1;
  }
  const int port = ntohs(address.sin_port);
  ::close(fd);
  return port;
}

/// A child process in a process group of its own (roscore starts rosmaster and rosout under it); stopped on
/// destruction: SIGINT to the group, SIGKILL after a grace period.
class Child {
 public:
  Child(const std::vector<std::string>& argv, const fs::path& log) {
    pid_ = ::fork();
    if (pid_ == 0) {
      ::setpgid(0, 0);
      const FILE* out = std::freopen(log.c_str(), "w", stdout);
      (void)out;
      ::dup2(STDOUT_FILENO, STDERR_FILENO);
      std::vector<char*> args;
      for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      ::execvp(args[0], args.data());
      std::_Exit(127);
    }
    if (pid_ > 0) ::setpgid(pid_, pid_);
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  ~Child() { stop(); }

  /// True while the process runs.
  bool running() {
    if (pid_ <= 0) return false;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      return false;
    }
    return true;
  }

  /// The exit code once the process has ended by itself, within `limit`; nothing if it still runs.
  std::optional<int> exit_code(std::chrono::seconds limit) {
    const auto end = Clock::now() + limit;
    while (pid_ > 0 && Clock::now() < end) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return std::nullopt;
  }

  void stop() {
    if (pid_ <= 0) return;
    ::kill(-pid_, SIGINT);
    for (int i = 0; i < 100; ++i) {  // up to 10 s for roslaunch to stop its children
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        ::kill(-pid_, SIGKILL);  // anything of the group still left
        pid_ = -1;
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    ::kill(-pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }

 private:
  pid_t pid_ = -1;
};

/// Waits until `done` holds, spinning ROS callbacks; false after `limit`.
bool wait_for(const std::function<bool()>& done, std::chrono::seconds limit) {
  const auto end = Clock::now() + limit;
  while (!done()) {
    if (Clock::now() > end || !ros::ok()) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

/// Calls a service of the node. A false from ros::service::call is a transport failure (the handlers under test
/// answer every valid request): on a loaded machine (CI runs these tests beside hundreds of others) the master's
/// lookup or the connection can fail once, so the call is retried a few times after waiting for the service.
/// A node that crashed stays unreachable and still fails the test.
template <typename S>
bool call_service(const std::string& name, S& service) {
  for (int attempt = 0; attempt < 5; ++attempt) {
    if (ros::service::call(name, service)) return true;
    ros::service::waitForService(name, ros::Duration(10.0));
  }
  return false;
}

std::string log_text(const fs::path& path) {
  const std::vector<std::uint8_t> bytes = read_bytes(path);
  return std::string(bytes.begin(), bytes.end());
}

/// The latest message on a topic, and how many came.
template <typename M>
struct Latest {
  std::mutex mutex;
  typename M::ConstPtr message;
  std::size_t count = 0;
  void take(const typename M::ConstPtr& m) {
    std::lock_guard lock(mutex);
    message = m;
    ++count;
  }
  typename M::ConstPtr get() {
    std::lock_guard lock(mutex);
    return message;
  }
};

std::vector<std::uint8_t> data_of(const octomap_msgs::Octomap& message) {
  return std::vector<std::uint8_t>(message.data.begin(), message.data.end());
}

/// `map` after ~clear_bbx of [low, high]: every known voxel in the box free at the clamping minimum, unknown ones
/// unknown. `known` receives how many voxels were known.
OccupancyMap cleared_box(const OccupancyMap& map, const Vec3d& low, const Vec3d& high, std::size_t& known) {
  OccupancyMap cleared = map;
  const Key from = cleared.key(low);
  const Key to = cleared.key(high);
  known = 0;
  for (std::uint32_t x = from.x; x <= to.x; ++x) {
    for (std::uint32_t y = from.y; y <= to.y; ++y) {
      for (std::uint32_t z = from.z; z <= to.z; ++z) {
        const Key key{x, y, z};
        if (map.node(key).state == OccupancyState::unknown) continue;
        cleared.set_log_odds(key, cleared.sensor_model().clamp_min_log_odds());
        ++known;
      }
    }
  }
  return cleared;
}

/// The value of `name: value` at the start of a line of the YAML rostopic and rosservice print; "(none)" if absent.
std::string yaml_value(const std::string& text, const std::string& name) {
  const std::string key = "\n" + name + ": ";
  const std::string padded = "\n" + text;
  const std::size_t at = padded.find(key);
  if (at == std::string::npos) return "(none)";
  const std::size_t start = at + key.size();
  return padded.substr(start, padded.find('\n', start) - start);
}

/// A double as YAML text that reads back to the same double.
std::string yaml_number(double value) {
  std::array<char, 32> text{};
  std::snprintf(text.data(), text.size(), "%.17g", value);
  return text.data();
}

/// Runs a ROS command-line tool in the shell with umbra's message types known (build/ros/messages/setup.sh),
/// talking to the test's roscore (ROS_MASTER_URI is in the environment). `timeout` only guards against a hang.
CommandResult ros_tool(const std::string& command) {
  return run_command(". " + std::string(UMBRA_ROS_MESSAGES_DIR) + "/setup.sh && timeout 300 " + command + " 2>&1");
}

/// One roscore and one ROS client for the whole test program (roscpp can be initialised once per process).
class RosMaster : public ::testing::Environment {
 public:
  void SetUp() override {
    if (std::system("command -v roscore > /dev/null 2>&1") != 0) {
      skip_reason_ = "roscore not found: install Debian's ros-core-dev (scripts/common.sh) to run the ROS loopback test";
      return;
    }
    dir_ = scratch_dir();
    const int port = free_port();
    ASSERT_GT(port, 0) << "no free port on 127.0.0.1";
    const std::string master = "http://127.0.0.1:" + std::to_string(port);
    ::setenv("ROS_MASTER_URI", master.c_str(), 1);
    ::setenv("ROS_HOSTNAME", "127.0.0.1", 1);
    ::unsetenv("ROS_IP");
    ::setenv("ROS_HOME", dir_.c_str(), 1);
    ::setenv("ROS_LOG_DIR", (dir_ / "log").c_str(), 1);
    ::setenv("ROSCONSOLE_STDOUT_LINE_BUFFERED", "1", 1);  // the nodes' INFO lines reach their logs at once
    roscore_ = std::make_unique<Child>(std::vector<std::string>{"roscore", "-p", std::to_string(port)}, dir_ / "roscore.log");
    int argc = 0;
    ros::init(argc, nullptr, "umbra_loopback_test", ros::init_options::NoSigintHandler | ros::init_options::AnonymousName);
    ASSERT_TRUE(wait_for([&] { return ros::master::check() || !roscore_->running(); }, kStartLimit) &&
                roscore_->running())
        << "roscore did not come up on " << master << ":\n" << log_text(dir_ / "roscore.log");
    node_ = std::make_unique<ros::NodeHandle>();
    spinner_ = std::make_unique<ros::AsyncSpinner>(1);
    spinner_->start();
  }

  void TearDown() override {
    if (spinner_) spinner_->stop();
    node_.reset();
    if (ros::isInitialized()) ros::shutdown();
    roscore_.reset();  // stops roscore, rosmaster and rosout
  }

  static inline std::string skip_reason_;
  static inline std::unique_ptr<ros::NodeHandle> node_;

 private:
  fs::path dir_;
  std::unique_ptr<Child> roscore_;
  std::unique_ptr<ros::AsyncSpinner> spinner_;
};

class Loopback : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!RosMaster::skip_reason_.empty()) GTEST_SKIP() << RosMaster::skip_reason_;
    ASSERT_TRUE(RosMaster::node_) << "no ROS master (see the environment's failure above)";
    node_ = RosMaster::node_.get();
    dir_ = scratch_dir();
  }

  void TearDown() override {
    binary_sub_.shutdown();
    full_sub_.shutdown();
    markers_sub_.shutdown();
    cloud_pub_.shutdown();
    tf_pub_.shutdown();
    depth_pub_.shutdown();
    info_pub_.shutdown();
    color_pub_.shutdown();
    server_.reset();  // stops umbra_server
  }

  /// Starts umbra_server with OctoMap's sensor model (umbra's defaults, as `umbra build` uses) and `params`.
  void start_server(double resolution, const std::vector<std::string>& params = {}) {
    // Private parameters outlive their node on the master: without this, a test would inherit the last one's
    // (~pointcloud_min_z, ~integrator, ...).
    ros::param::del("/umbra_server");
    std::vector<std::string> argv{UMBRA_SERVER_PATH,
                                  "cloud_in:=/robot/points",
                                  "depth/image:=/camera/depth/image_rect_raw",
                                  "_frame_id:=/map",
                                  "_resolution:=" + std::to_string(resolution),
                                  "_sensor_model/min:=0.1192",
                                  "_sensor_model/max:=0.971",
                                  "_threads:=2"};
    argv.insert(argv.end(), params.begin(), params.end());
    server_ = std::make_unique<Child>(argv, dir_ / "umbra_server.log");
    binary_sub_ = node_->subscribe<octomap_msgs::Octomap>("/octomap_binary", 5,
                                                          [this](const octomap_msgs::Octomap::ConstPtr& m) { binary_.take(m); });
    full_sub_ = node_->subscribe<octomap_msgs::Octomap>("/octomap_full", 5,
                                                        [this](const octomap_msgs::Octomap::ConstPtr& m) { full_.take(m); });
    markers_sub_ = node_->subscribe<visualization_msgs::MarkerArray>(
        "/occupied_cells_vis_array", 5, [this](const visualization_msgs::MarkerArray::ConstPtr& m) { markers_.take(m); });
    cloud_pub_ = node_->advertise<sensor_msgs::PointCloud2>("/robot/points", 10);
    tf_pub_ = node_->advertise<tf2_msgs::TFMessage>("/tf", 100);
    // A camera driver's topics; the node's depth/image is remapped to the image, and finds the CameraInfo
    // beside it (image_transport's rule). The color image is remapped only where a test asks for colors.
    depth_pub_ = node_->advertise<sensor_msgs::Image>("/camera/depth/image_rect_raw", 10);
    info_pub_ = node_->advertise<sensor_msgs::CameraInfo>("/camera/depth/camera_info", 10);
    color_pub_ = node_->advertise<sensor_msgs::Image>("/camera/color/image_raw", 10);
    ASSERT_TRUE(wait_for([&] { return (cloud_pub_.getNumSubscribers() > 0 && tf_pub_.getNumSubscribers() > 0 &&
                                       depth_pub_.getNumSubscribers() > 0 && info_pub_.getNumSubscribers() > 0) ||
                                      !server_->running(); },
                         kStartLimit) &&
                server_->running())
        << "umbra_server did not subscribe to the cloud, /tf, the depth image and its CameraInfo:\n"
        << log_text(dir_ / "umbra_server.log");
  }

  /// Publishes the scans one at a time (pose first), each time waiting for both maps with its stamp.
  void publish(const std::vector<RosScan>& scans, double first_time) {
    for (std::size_t i = 0; i < scans.size(); ++i) {
      const ros::Time stamp(first_time + 0.1 * static_cast<double>(i));
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(to_transform(scans[i], "map", "lidar", stamp));
      const sensor_msgs::PointCloud2 cloud = to_cloud(scans[i], "lidar", stamp);
      const auto send = [&] {
        tf_pub_.publish(tf);
        cloud_pub_.publish(cloud);
      };
      send();
      const bool arrived = wait_or_resend(
          [&] {
            const auto b = binary_.get();
            const auto f = full_.get();
            return b && f && b->header.stamp == stamp && f->header.stamp == stamp;
          },
          send, "scan " + std::to_string(i));
      ASSERT_TRUE(arrived) << "no map for scan " << i << " at " << stamp << ":\n" << log_text(dir_ / "umbra_server.log");
    }
  }

  /// Checks the last published maps against `expected`.
  void expect_published(const OccupancyMap& expected) {
    const auto binary = binary_.get();
    const auto full = full_.get();
    ASSERT_TRUE(binary && full);
    EXPECT_TRUE(binary->binary);
    EXPECT_FALSE(full->binary);
    EXPECT_EQ(binary->id, "OcTree");
    EXPECT_EQ(binary->header.frame_id, "map");
    EXPECT_EQ(binary->resolution, expected.resolution());
    EXPECT_EQ(data_of(*binary), tree_bytes(expected, OctoMapFormat::bt));
    EXPECT_EQ(data_of(*full), tree_bytes(expected, OctoMapFormat::ot));
    // Decoded with umbra's reader: the same map, leaf by leaf.
    const OccupancyMap decoded = ros_io::map_from_message(*full);
    EXPECT_EQ(tree_bytes(decoded, OctoMapFormat::ot), tree_bytes(expected, OctoMapFormat::ot));
  }

  /// Publishes `cloud` (frame map, no transform needed) and waits for the maps with its stamp, a log line saying
  /// the node cannot insert it, or the node's end; true when the maps came.
  bool insert(const sensor_msgs::PointCloud2& cloud) {
    const fs::path log = dir_ / "umbra_server.log";
    const std::string name = "cloud in frame 'map' at " + std::to_string(cloud.header.stamp.toSec());
    cloud_pub_.publish(cloud);
    bool mapped = false;
    EXPECT_TRUE(wait_for(
        [&] {
          const auto b = binary_.get();
          const auto f = full_.get();
          mapped = b && f && b->header.stamp == cloud.header.stamp && f->header.stamp == cloud.header.stamp;
          return mapped || log_text(log).find("cannot insert the " + name) != std::string::npos || !server_->running();
        },
        kMessageLimit))
        << "neither a map nor an error for the " << name << ":\n" << log_text(log);
    return mapped;
  }

  /// Publishes a depth image with its CameraInfo (and color image) and waits for the maps with its stamp, a log
  /// line saying the node cannot insert it, or the node's end; true when the maps came.
  /// Publishes the transform of the next depth image (sent again with it, if it must be: kResendAfter).
  void publish_image_tf(const tf2_msgs::TFMessage& tf) {
    last_tf_ = tf;
    tf_pub_.publish(tf);
  }

  /// wait_for(done), sending the messages once more after kResendAfter (see there).
  bool wait_or_resend(const std::function<bool()>& done, const std::function<void()>& send, const std::string& what) {
    if (wait_for(done, kResendAfter)) return true;
    std::cerr << "no answer for " << what << " in " << kResendAfter.count() << " s: sending it again\n";
    send();
    return wait_for(done, kMessageLimit);
  }

  bool insert_image(const sensor_msgs::Image& depth, const sensor_msgs::CameraInfo& info,
                    const sensor_msgs::Image* color = nullptr) {
    const fs::path log = dir_ / "umbra_server.log";
    const std::string name = "depth image in frame '" + depth.header.frame_id + "' at " +
                             std::to_string(depth.header.stamp.toSec());
    const auto send = [&] {
      if (last_tf_) tf_pub_.publish(*last_tf_);
      info_pub_.publish(info);
      if (color != nullptr) color_pub_.publish(*color);
      depth_pub_.publish(depth);
    };
    send();
    bool mapped = false;
    EXPECT_TRUE(wait_or_resend(
        [&] {
          const auto b = binary_.get();
          const auto f = full_.get();
          mapped = b && f && b->header.stamp == depth.header.stamp && f->header.stamp == depth.header.stamp;
          return mapped || log_text(log).find("cannot insert the " + name) != std::string::npos || !server_->running();
        },
        send, "the " + name))
        << "neither a map nor an error for the " << name << ":\n" << log_text(log);
    return mapped;
  }

  fs::path dir_;
  ros::NodeHandle* node_ = nullptr;
  std::unique_ptr<Child> server_;
  ros::Subscriber binary_sub_;
  ros::Subscriber full_sub_;
  ros::Subscriber markers_sub_;
  ros::Publisher cloud_pub_;
  ros::Publisher tf_pub_;
  ros::Publisher depth_pub_;
  ros::Publisher info_pub_;
  ros::Publisher color_pub_;
  Latest<octomap_msgs::Octomap> binary_;
  Latest<octomap_msgs::Octomap> full_;
  Latest<visualization_msgs::MarkerArray> markers_;
  std::optional<tf2_msgs::TFMessage> last_tf_;  ///< publish_image_tf's
};

TEST_F(Loopback, NodeMapEqualsUmbraBuild) {
  const double resolution = 0.1;
  const std::vector<RosScan> scans = office_scans(6);
  ASSERT_NO_FATAL_FAILURE(start_server(resolution));
  ASSERT_NO_FATAL_FAILURE(publish(scans, 1000.0));

  // `umbra build` on a bag of the same messages, and the library on the simulator's points.
  {
    rosbag::Bag bag((dir_ / "same.bag").string(), rosbag::bagmode::Write);
    for (std::size_t i = 0; i < scans.size(); ++i) {
      const ros::Time stamp(1000.0 + 0.1 * static_cast<double>(i));
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(to_transform(scans[i], "map", "lidar", stamp));
      bag.write("/tf", stamp, tf);
      bag.write("/robot/points", stamp, to_cloud(scans[i], "lidar", stamp));
    }
  }
  const CommandResult built = run_command(std::string(UMBRA_CLI_PATH) + " build " + (dir_ / "same.bag").string() +
                                          " --frame map --res 0.1 -o " + (dir_ / "same.umb").string() + " 2>&1");
  ASSERT_EQ(built.exit_code, 0) << built.output;
  const OccupancyMap from_cli = load_map(dir_ / "same.umb");
  const OccupancyMap reference = reference_map(scans, resolution);
  EXPECT_EQ(tree_bytes(from_cli, OctoMapFormat::ot), tree_bytes(reference, OctoMapFormat::ot));
  ASSERT_NO_FATAL_FAILURE(expect_published(from_cli));

  // The occupied-cell markers list the occupied leaves.
  ASSERT_TRUE(wait_for([&] { auto m = markers_.get(); return m && !m->markers.empty() && m->markers[0].header.stamp == ros::Time(1000.5); },
                       kMessageLimit));
  std::size_t cubes = 0;
  for (const auto& marker : markers_.get()->markers) cubes += marker.points.size();
  std::size_t occupied = 0;
  reference.for_each_leaf([&](const Node& leaf) { occupied += leaf.state == OccupancyState::occupied ? 1 : 0; });
  EXPECT_EQ(cubes, occupied);
  EXPECT_GT(occupied, 100u);

  // ~clear_bbx: every known voxel in the box becomes free (clamping minimum); unknown ones stay unknown.
  octomap_msgs::BoundingBoxQuery box;
  box.request.min.x = 2.0;
  box.request.min.y = 4.0;
  box.request.min.z = -0.5;
  box.request.max.x = 3.2;
  box.request.max.y = 7.5;
  box.request.max.z = 1.0;
  const std::size_t before = full_.count;
  ASSERT_TRUE(call_service("/umbra_server/clear_bbx", box));
  ASSERT_TRUE(wait_for([&] { return full_.count > before; }, kMessageLimit));
  std::size_t known = 0;
  const OccupancyMap cleared = cleared_box(reference, {2.0, 4.0, -0.5}, {3.2, 7.5, 1.0}, known);
  EXPECT_GT(known, 1000u);
  ASSERT_TRUE(wait_for([&] { return full_.get() && binary_.get() && binary_.count == full_.count; }, kMessageLimit));
  ASSERT_NO_FATAL_FAILURE(expect_published(cleared));

  // ~check_collision: the library's is_free on the map the node holds (the cleared one).
  {
    std::mt19937 rng(12);
    std::uniform_real_distribution<double> x(0.5, 19.5), y(0.5, 11.5), z(0.2, 2.8), r(0.05, 0.6);
    std::size_t free_answers = 0;
    std::size_t blocked_by_unknown = 0;
    for (int i = 0; i < 60; ++i) {
      umbra_msgs::CheckCollision check;
      const Vec3d a{x(rng), y(rng), z(rng)};
      const Vec3d b{x(rng), y(rng), z(rng)};
      check.request.shape = static_cast<std::uint8_t>(i % 4);
      check.request.a.x = a.x;
      check.request.a.y = a.y;
      check.request.a.z = a.z;
      check.request.b.x = i % 4 == 1 ? a.x + 0.3 : b.x;  // a box: a small one above a
      check.request.b.y = i % 4 == 1 ? a.y + 0.4 : b.y;
      check.request.b.z = i % 4 == 1 ? a.z + 0.2 : b.z;
      check.request.radius = r(rng);
      check.request.unknown_is_free = i % 3 == 0;
      check.request.depth = i % 5 == 0 ? 2 : 0;
      ASSERT_TRUE(call_service("/umbra_server/check_collision", check));
      ASSERT_TRUE(check.response.valid) << check.response.error;
      const CollisionOptions options{check.request.unknown_is_free != 0, check.request.depth};
      CollisionResult want;
      switch (i % 4) {
        case 0: want = cleared.is_free(Sphere{a, check.request.radius}, options); break;
        case 1: want = cleared.is_free(Aabb{a, {a.x + 0.3, a.y + 0.4, a.z + 0.2}}, options); break;
        case 2: want = cleared.is_free(Capsule{a, b, check.request.radius}, options); break;
        default: want = cleared.is_free(Segment{a, b}, options); break;
      }
      EXPECT_EQ(check.response.free, want.free) << "check " << i;
      if (!want.free) {
        EXPECT_EQ(check.response.blocking_center.x, want.blocking->center.x) << "check " << i;
        EXPECT_EQ(check.response.blocking_size, want.blocking->size) << "check " << i;
        EXPECT_EQ(int{check.response.blocking_state}, want.blocking->contains_occupied()
                                                          ? int{umbra_msgs::CheckCollision::Response::OCCUPIED}
                                                          : int{umbra_msgs::CheckCollision::Response::UNKNOWN})
            << "check " << i;
        blocked_by_unknown += want.blocking->contains_occupied() ? 0 : 1;
      } else {
        EXPECT_EQ(int{check.response.blocking_state}, int{umbra_msgs::CheckCollision::Response::NONE}) << "check " << i;
      }
      free_answers += want.free ? 1 : 0;
    }
    EXPECT_GT(free_answers, 0u);
    EXPECT_LT(free_answers, 60u);
    EXPECT_GT(blocked_by_unknown, 0u);  // both kinds of blocking node were seen
    EXPECT_LT(blocked_by_unknown, 60u - free_answers);
    // A bad request: an answer saying why, not a failed call.
    umbra_msgs::CheckCollision bad;
    bad.request.shape = umbra_msgs::CheckCollision::Request::SPHERE;
    bad.request.radius = -1.0;
    ASSERT_TRUE(call_service("/umbra_server/check_collision", bad));
    EXPECT_FALSE(bad.response.valid);
    EXPECT_NE(bad.response.error.find("radius"), std::string::npos) << bad.response.error;
  }

  // ~merge: another map (the library's of the first scans, as a full message) added with an offset; the node
  // then publishes the library's merge of the same maps. Refused requests leave the map and say why.
  {
    const std::vector<RosScan> first_scans(scans.begin(), scans.begin() + 2);
    umbra_msgs::MergeMap merge;
    merge.request.map = ros_io::octomap_message(reference_map(first_scans, resolution), OctoMapFormat::ot, "map",
                                                ros::Time::now());
    merge.request.offset_x = 3;
    merge.request.offset_y = -2;
    OccupancyMap merged = cleared;
    const MergeStats stats = merged.merge(ros_io::map_from_message(merge.request.map), VoxelOffset{3, -2, 0});
    const std::size_t before_merge = full_.count;
    ASSERT_TRUE(call_service("/umbra_server/merge", merge));
    EXPECT_TRUE(merge.response.success) << merge.response.error;
    EXPECT_EQ(merge.response.voxels, stats.voxels);
    ASSERT_TRUE(wait_for([&] { return full_.count > before_merge && binary_.count == full_.count; }, kMessageLimit));
    ASSERT_NO_FATAL_FAILURE(expect_published(merged));

    umbra_msgs::MergeMap coarse;
    coarse.request.map = ros_io::octomap_message(reference_map(first_scans, 0.2), OctoMapFormat::ot, "map",
                                                 ros::Time::now());
    ASSERT_TRUE(call_service("/umbra_server/merge", coarse));
    EXPECT_FALSE(coarse.response.success);
    EXPECT_NE(coarse.response.error.find("resolutions differ"), std::string::npos) << coarse.response.error;
    umbra_msgs::MergeMap elsewhere = merge;
    elsewhere.request.map.header.frame_id = "odom";
    ASSERT_TRUE(call_service("/umbra_server/merge", elsewhere));
    EXPECT_FALSE(elsewhere.response.success);
    EXPECT_NE(elsewhere.response.error.find("'odom'"), std::string::npos) << elsewhere.response.error;
    ASSERT_NO_FATAL_FAILURE(expect_published(merged));
  }

  // ~reset: an empty map.
  std_srvs::Empty empty;
  const std::size_t before_reset = full_.count;
  ASSERT_TRUE(call_service("/umbra_server/reset", empty));
  ASSERT_TRUE(wait_for([&] { return full_.count > before_reset && binary_.count == full_.count; }, kMessageLimit));
  EXPECT_TRUE(full_.get()->data.empty());
  EXPECT_TRUE(binary_.get()->data.empty());
}

// projected_map (nav_msgs/OccupancyGrid) after every scan equals the offline projection (project_to_grid, itself
// checked against brute force in tests/query/) of the library's map of the same scans, over the band
// ~occupancy_min_z .. ~occupancy_max_z; and with unbounded heights (octomap_server's defaults) the whole map.
TEST_F(Loopback, ProjectedMapEqualsTheOfflineProjectionAfterEveryScan) {
  const double resolution = 0.1;
  const std::vector<RosScan> scans = office_scans(4);
  struct Run {
    std::vector<std::string> params;
    ProjectionOptions options;  ///< what the parameters mean (unbounded: the map's extent, 3276.8 m at 0.1 m)
  };
  const std::vector<Run> runs = {
      {{"_occupancy_min_z:=0.15", "_occupancy_max_z:=1.25", "_projected_map_rule:=all_known"},
       {0.15, 1.25, 0, ProjectionRule::all_known}},
      {{"_occupancy_min_z:=0.15", "_occupancy_max_z:=1.25", "_projected_map_depth:=1"},
       {0.15, 1.25, 1, ProjectionRule::any_free}},
      {{}, {-3276.8, 3276.8, 0, ProjectionRule::any_free}},  // octomap_server's defaults
  };
  for (const Run& run : runs) {
    const ProjectionOptions& options = run.options;
    SCOPED_TRACE("z " + std::to_string(options.z_min) + " .. " + std::to_string(options.z_max) + " depth " +
                 std::to_string(options.depth) + " rule " + std::string(to_string(options.rule)));
    Latest<nav_msgs::OccupancyGrid> projected;
    ros::Subscriber projected_sub = node_->subscribe<nav_msgs::OccupancyGrid>(
        "/projected_map", 5, [&](const nav_msgs::OccupancyGrid::ConstPtr& m) { projected.take(m); });
    ASSERT_NO_FATAL_FAILURE(start_server(resolution, run.params));
    std::array<std::size_t, 3> kinds{};  // occupied, free, unknown cells compared, over all scans
    for (std::size_t i = 0; i < scans.size(); ++i) {
      const ros::Time stamp(3000.0 + 0.1 * static_cast<double>(i));
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(to_transform(scans[i], "map", "lidar", stamp));
      tf_pub_.publish(tf);
      cloud_pub_.publish(to_cloud(scans[i], "lidar", stamp));
      ASSERT_TRUE(wait_for([&] { const auto m = projected.get(); return m && m->header.stamp == stamp; },
                           kMessageLimit))
          << "no projected map for scan " << i << ":\n" << log_text(dir_ / "umbra_server.log");
      const auto got = projected.get();
      const std::vector<RosScan> so_far(scans.begin(), scans.begin() + static_cast<std::ptrdiff_t>(i) + 1);
      const NavigationGrid want = project_to_grid(reference_map(so_far, resolution), options);
      ASSERT_FALSE(want.empty());
      EXPECT_EQ(got->header.frame_id, "map");
      EXPECT_EQ(got->info.resolution, static_cast<float>(want.resolution));
      EXPECT_EQ(got->info.origin.position.x, want.origin_x);
      EXPECT_EQ(got->info.origin.position.y, want.origin_y);
      EXPECT_EQ(got->info.origin.orientation.w, 1.0);
      ASSERT_EQ(got->info.width, want.width) << "scan " << i;
      ASSERT_EQ(got->info.height, want.height) << "scan " << i;
      ASSERT_EQ(got->data.size(), want.cells.size());
      std::size_t differ = 0;
      for (std::size_t k = 0; k < want.cells.size(); ++k) {
        differ += got->data[k] != static_cast<std::int8_t>(want.cells[k]) ? 1 : 0;
        ++kinds[want.cells[k] == GridCell::occupied ? 0 : want.cells[k] == GridCell::free ? 1 : 2];
      }
      EXPECT_EQ(differ, 0u) << "cells differ after scan " << i;
    }
    // Every value occurred, or the comparison proves little.
    EXPECT_GT(kinds[0], 10u);
    EXPECT_GT(kinds[1], 10u);
    EXPECT_GT(kinds[2], 10u);
    projected_sub.shutdown();
    server_.reset();
  }
}

// Issue 23, item 7: ROS's command-line tools on the node, as a user types them. rostopic needs Debian's
// python3-sensor-msgs for the centres; the Octomap topic and the services of octomap_msgs and umbra_msgs need the
// Python modules and package folders the build generates (build/ros/messages, ros/generate_python_messages.py).
TEST_F(Loopback, CommandLineToolsEchoTopicsAndCallServices) {
  ASSERT_FALSE(std::string(UMBRA_ROS_MESSAGES_DIR).empty())
      << "CMake found no genpy (Debian: python3-genpy, scripts/common.sh): the Python message modules are not built";
  const double resolution = 0.1;
  const std::vector<RosScan> scans = office_scans(3);
  ASSERT_NO_FATAL_FAILURE(start_server(resolution));
  ASSERT_NO_FATAL_FAILURE(publish(scans, 4000.0));
  const OccupancyMap reference = reference_map(scans, resolution);
  ASSERT_NO_FATAL_FAILURE(expect_published(reference));

  // The latched centres of the occupied cells: one point per occupied leaf.
  const CommandResult centers = ros_tool("rostopic echo -n 1 --noarr /octomap_point_cloud_centers");
  ASSERT_EQ(centers.exit_code, 0) << centers.output;
  std::size_t occupied = 0;
  reference.for_each_leaf([&](const Node& leaf) { occupied += leaf.state == OccupancyState::occupied ? 1 : 0; });
  EXPECT_GT(occupied, 100u);
  EXPECT_EQ(yaml_value(centers.output, "width"), std::to_string(occupied)) << centers.output;
  EXPECT_EQ(yaml_value(centers.output, "  frame_id"), "\"map\"") << centers.output;
  EXPECT_EQ(yaml_value(centers.output, "    secs"), "4000") << centers.output;

  const CommandResult binary = ros_tool("rostopic echo -n 1 --noarr /octomap_binary");
  ASSERT_EQ(binary.exit_code, 0) << binary.output;
  EXPECT_EQ(yaml_value(binary.output, "id"), "\"OcTree\"") << binary.output;
  EXPECT_EQ(yaml_value(binary.output, "binary"), "True") << binary.output;
  EXPECT_EQ(yaml_value(binary.output, "resolution"), "0.1") << binary.output;

  // ~clear_bbx (octomap_msgs/BoundingBoxQuery) from rosservice: the node's map is the cleared one.
  const std::size_t before_clear = full_.count;
  const CommandResult clear = ros_tool(
      "rosservice call /umbra_server/clear_bbx '{min: {x: 2.0, y: 4.0, z: -0.5}, max: {x: 3.2, y: 7.5, z: 1.0}}'");
  ASSERT_EQ(clear.exit_code, 0) << clear.output;
  ASSERT_TRUE(wait_for([&] { return full_.count > before_clear && binary_.count == full_.count; }, kMessageLimit));
  std::size_t known = 0;
  const OccupancyMap cleared = cleared_box(reference, {2.0, 4.0, -0.5}, {3.2, 7.5, 1.0}, known);
  EXPECT_GT(known, 1000u);
  ASSERT_NO_FATAL_FAILURE(expect_published(cleared));

  // ~check_collision (umbra_msgs/CheckCollision) from rosservice: the library's answer on the cleared map, and
  // why the blocking node blocks. A free voxel, an occupied one, and a ball far out in space never seen (a
  // large unknown node, the "51.2 m node").
  std::optional<Vec3d> free_voxel;
  std::optional<Vec3d> occupied_voxel;
  cleared.for_each_leaf([&](const Node& leaf) {
    if (leaf.depth != 0) return;
    if (leaf.state == OccupancyState::free && !free_voxel) free_voxel = leaf.center;
    if (leaf.state == OccupancyState::occupied && !occupied_voxel) occupied_voxel = leaf.center;
  });
  ASSERT_TRUE(free_voxel && occupied_voxel);
  struct Check {
    Vec3d center;
    double radius;
    int state;  // the expected blocking_state: 0 free, 1 occupied, 2 unknown
  };
  for (const Check& c : {Check{*free_voxel, 0.01, 0}, Check{*occupied_voxel, 0.01, 1}, Check{{60.0, 60.0, 1.0}, 0.3, 2}}) {
    const CommandResult answer = ros_tool(
        "rosservice call /umbra_server/check_collision '{shape: 0, a: {x: " + yaml_number(c.center.x) + ", y: " +
        yaml_number(c.center.y) + ", z: " + yaml_number(c.center.z) + "}, radius: " + yaml_number(c.radius) +
        ", unknown_is_free: false, depth: 0}'");
    ASSERT_EQ(answer.exit_code, 0) << answer.output;
    const CollisionResult want = cleared.is_free(Sphere{c.center, c.radius}, {false, 0});
    EXPECT_EQ(yaml_value(answer.output, "valid"), "True") << answer.output;
    EXPECT_EQ(yaml_value(answer.output, "free"), want.free ? "True" : "False") << answer.output;
    EXPECT_EQ(yaml_value(answer.output, "blocking_state"), std::to_string(c.state)) << answer.output;
    if (c.state == 0) {
      EXPECT_TRUE(want.free);
      continue;
    }
    ASSERT_FALSE(want.free);
    EXPECT_EQ(want.blocking->contains_occupied(), c.state == 1);
    EXPECT_EQ(std::stod(yaml_value(answer.output, "blocking_size")), want.blocking->size) << answer.output;
  }

  // ~reset (std_srvs/Empty, python3-std-srvs).
  const std::size_t before_reset = full_.count;
  const CommandResult reset = ros_tool("rosservice call /umbra_server/reset");
  ASSERT_EQ(reset.exit_code, 0) << reset.output;
  ASSERT_TRUE(wait_for([&] { return full_.count > before_reset && binary_.count == full_.count; }, kMessageLimit));
  EXPECT_TRUE(full_.get()->data.empty());
}

// Issue 23, item 7: a cloud in a frame TF does not name used to wait in tf2's filter without a word. The node
// names the frames it maps and serves at start-up, warns about a cloud waiting for its transform (naming the
// cloud's frame, the map frame and the frames tf2 knows), inserts it once the transform comes, and names the
// clouds the filter drops.
TEST_F(Loopback, CloudsWithoutTransformAreNamedInAWarning) {
  ASSERT_NO_FATAL_FAILURE(start_server(0.1));
  const fs::path log = dir_ / "umbra_server.log";
  // The log line that starts with `start`, without roscpp's color codes around it.
  const auto line_of = [&](const std::string& start) {
    const std::string text = log_text(log);
    const std::size_t at = text.find(start);
    return at == std::string::npos ? std::string("(no line '" + start + "' in:\n" + text + ")")
                                   : text.substr(at, text.find_first_of("\n\x1B", at) - at);
  };
  const auto logged = [&](const std::string& part) {
    return wait_for([&] { return log_text(log).find(part) != std::string::npos; }, kMessageLimit);
  };
  ASSERT_TRUE(logged("umbra_server: publishing")) << log_text(log);
  EXPECT_EQ(line_of("umbra_server: mapping in frame"),
            "umbra_server: mapping in frame 'map' at 0.1 m (integrator simple): clouds from '/robot/points' and depth "
            "images from '/camera/depth/image_rect_raw' with '/camera/depth/camera_info', each once TF can move its "
            "frame into 'map'");
  EXPECT_EQ(line_of("umbra_server: publishing"),
            "umbra_server: publishing '/octomap_binary', '/octomap_full', '/occupied_cells_vis_array', "
            "'/octomap_point_cloud_centers', '/projected_map'; services '/octomap_binary', '/octomap_full', "
            "'/umbra_server/reset', "
            "'/umbra_server/clear_bbx', '/umbra_server/check_collision', '/umbra_server/merge'");

  // TF knows map -> lidar, not the frame of the cloud.
  const std::vector<RosScan> scans = office_scans(1);
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(to_transform(scans[0], "map", "lidar", ros::Time(8000.0)));
  tf_pub_.publish(tf);
  cloud_pub_.publish(to_cloud(scans[0], "nowhere", ros::Time(8000.0)));
  ASSERT_TRUE(logged("umbra_server: 1 cloud has waited")) << log_text(log);
  const std::string waited = line_of("umbra_server: 1 cloud has waited");
  EXPECT_NE(waited.find("for a transform from 'nowhere' to the map frame 'map' (the latest at 8000.000000); none is "
                        "inserted until TF connects the two (frames tf2 knows: "),
            std::string::npos)
      << waited;
  EXPECT_NE(waited.find("'lidar'"), std::string::npos) << waited;
  EXPECT_NE(waited.find("'map'"), std::string::npos) << waited;

  // Its transform comes: the cloud is inserted.
  tf.transforms[0] = to_transform(scans[0], "map", "nowhere", ros::Time(8000.0));
  tf_pub_.publish(tf);
  ASSERT_TRUE(wait_for([&] { const auto b = binary_.get(); return b && b->header.stamp == ros::Time(8000.0); },
                       kMessageLimit))
      << log_text(log);
  ASSERT_NO_FATAL_FAILURE(expect_published(reference_map(scans, 0.1)));

  // Clouds of another unknown frame: held until 5 newer ones push them out of the queue, then named.
  int published = 0;
  EXPECT_TRUE(wait_for(
      [&] {
        if (log_text(log).find("dropped the cloud in frame 'elsewhere'") != std::string::npos) return true;
        if (published < 1000) cloud_pub_.publish(to_cloud(scans[0], "elsewhere", ros::Time(8001.0 + 0.01 * published++)));
        return false;
      },
      kMessageLimit))
      << log_text(log);
  const std::string dropped = line_of("umbra_server: dropped the cloud in frame 'elsewhere' at 8001.000000");
  EXPECT_NE(dropped.find(": tf2 had no transform from 'elsewhere' to the map frame 'map' at its stamp (frames tf2 "
                         "knows: "),
            std::string::npos)
      << dropped;
  EXPECT_NE(dropped.find("'nowhere'"), std::string::npos) << dropped;
  EXPECT_NE(dropped.find("(clouds dropped so far: 1)"), std::string::npos) << dropped;
  EXPECT_GE(published, 6);
  EXPECT_TRUE(server_->running()) << log_text(log);
}

TEST_F(Loopback, IntegratorRangeAndHeightParameters) {
  const double resolution = 0.1;
  const std::vector<RosScan> scans = office_scans(3);
  ASSERT_NO_FATAL_FAILURE(start_server(resolution, {"_integrator:=fast", "_fine_steps:=1", "_clear_depth:=2",
                                                    "_sensor_model/max_range:=8.0", "_pointcloud_min_z:=0.5",
                                                    "_pointcloud_max_z:=2.0"}));
  ASSERT_NO_FATAL_FAILURE(publish(scans, 3000.0));
  // The library with the same settings on the points whose z lies in [0.5, 2.0].
  OccupancyMap expected(resolution, kOctoMapDepthLevels);
  InsertOptions options;
  options.integrator = IntegratorKind::fast;
  options.fine_steps = 1;
  options.clear_depth = 2;
  options.max_range = 8.0;
  std::size_t dropped = 0;
  for (const RosScan& scan : scans) {
    std::vector<Vec3f> kept;
    for (const Vec3f& p : scan.points) {
      if (p.z >= 0.5f && p.z <= 2.0f) kept.push_back(p);
    }
    dropped += scan.points.size() - kept.size();
    expected.insert_point_cloud(Vec3f(scan.position), kept, options);
  }
  EXPECT_GT(dropped, 1000u);  // the floor, at least
  ASSERT_NO_FATAL_FAILURE(expect_published(expected));
  // Not the map of the unfiltered points.
  EXPECT_NE(data_of(*full_.get()), tree_bytes(reference_map(scans, resolution), OctoMapFormat::ot));
}

/// Decay toward unknown on the clock of the clouds' stamps: two scans, then
/// one three seconds later; the published map is the library's with the
/// same rates and stamps, in which the first scans' obstacles are unknown.
TEST_F(Loopback, DecayParametersForgetAnObstacle) {
  const double resolution = 0.1;
  const std::vector<RosScan> scans = office_scans(2);
  ASSERT_NO_FATAL_FAILURE(start_server(resolution, {"_decay/occupied_per_second:=2.0", "_decay/free_per_second:=1.0"}));
  ASSERT_NO_FATAL_FAILURE(publish(scans, 4000.0));
  RosScan late;
  late.position = scans[0].position;
  late.points = {Vec3f(scans[0].position) + Vec3f{1.0f, 0.0f, 0.0f}};
  ASSERT_NO_FATAL_FAILURE(publish({late}, 4003.0));

  OccupancyMap expected(resolution, kOctoMapDepthLevels);
  expected.set_decay({2.0, 1.0, std::nullopt});
  InsertOptions options;
  const auto insert = [&](const RosScan& scan, double time) {
    options.stamp = ros::Time(time).toSec();  // the server's clock: the stamp as ROS stores it
    expected.insert_point_cloud(Vec3f(scan.position), scan.points, options);
  };
  insert(scans[0], 4000.0);
  // An obstacle of the first scan: occupied now, unknown once forgotten.
  const Vec3f obstacle = scans[0].points[scans[0].points.size() / 2];
  ASSERT_EQ(expected.state(Vec3d(obstacle)), OccupancyState::occupied);
  insert(scans[1], 4000.1);
  insert(late, 4003.0);
  EXPECT_EQ(expected.state(Vec3d(obstacle)), OccupancyState::unknown);
  ASSERT_NO_FATAL_FAILURE(expect_published(expected));
}

/// A map that moves: the server keeps a box around each cloud's sensor origin
/// and appends what leaves it to the spill file; the published map is the
/// library's with the same window, and the file holds the pieces the
/// library's window handed out.
TEST_F(Loopback, WindowParametersKeepABoxAroundTheSensor) {
  const double resolution = 0.1;
  const std::vector<RosScan> scans = office_scans(4);
  const fs::path spill = dir_ / "run.umbs";
  ASSERT_NO_FATAL_FAILURE(
      start_server(resolution, {"_window/half_extent:=1.0", "_window/spill_path:=" + spill.string()}));
  ASSERT_NO_FATAL_FAILURE(publish(scans, 4000.0));

  OccupancyMap expected(resolution, kOctoMapDepthLevels);
  OccupancyMap without_window(resolution, kOctoMapDepthLevels);
  std::vector<OccupancyMap> pieces;
  MovingWindow window;
  window.half_extent = 1.0;
  window.spill = [&](const OccupancyMap& piece) { pieces.push_back(piece); };
  expected.set_moving_window(window);
  for (const RosScan& scan : scans) {
    expected.insert_point_cloud(Vec3f(scan.position), scan.points);
    without_window.insert_point_cloud(Vec3f(scan.position), scan.points);
  }
  ASSERT_LT(expected.node_counts().total(), without_window.node_counts().total()) << "the window changed nothing";
  ASSERT_NO_FATAL_FAILURE(expect_published(expected));
  if (pieces.empty()) {
    EXPECT_FALSE(fs::exists(spill));
  } else {
    EXPECT_EQ(for_each_spill_piece(spill, [](OccupancyMap&&) {}), pieces.size());
  }
}

TEST_F(Loopback, BadParametersStopTheNodeWithAMessage) {
  const std::vector<std::pair<std::string, std::string>> cases{
      {"_integrator:=bogus", "bad parameter ~integrator"},
      {"_resolution:=-0.1", "bad parameter ~resolution"},
      {"_sensor_model/hit:=0.3", "bad parameter ~sensor_model/{hit,miss,min,max}"},
      {"_image_integrator:=rays", "bad parameter ~image_integrator"},
      {"_decay/occupied_per_second:=-1.0", "bad parameter ~decay/{occupied_per_second,free_per_second}: decay rate "
                                           "occupied_per_second must be finite and >= 0"},
      {"_image_colors:=true", "bad parameter ~image_colors: true needs ~keep_colors true"},
      {"_window/half_extent:=-2.0", "bad parameter ~window/half_extent: -2.000000"},
      {"_window/spill_path:=/tmp/x.umbs", "bad parameter ~window/spill_path: '/tmp/x.umbs' needs ~window/half_extent > 0"},
      {"_projected_map_rule:=most_free",
       "bad parameter ~projected_map_rule: unknown projection rule 'most_free' (the rules: all_known, any_free)"},
      {"_projected_map_depth:=17", "bad parameter ~projected_map_depth: 17 (must be 0 to 16)"},
      {"_occupancy_min_z:=1.5 _occupancy_max_z:=1.0",
       "bad parameters ~occupancy_min_z 1.500000 and ~occupancy_max_z 1.000000: the minimum must be below the maximum"},
  };
  int run = 0;
  for (const auto& [argument, expected] : cases) {
    const fs::path log = dir_ / "bad.log";
    // A name of its own: private parameters stay on the master after a node ends.
    std::vector<std::string> argv{UMBRA_SERVER_PATH};
    std::istringstream words(argument);  // one or more parameters
    for (std::string word; words >> word;) argv.push_back(word);
    argv.push_back("__name:=umbra_server_bad_" + std::to_string(run++));
    Child server(argv, log);
    const std::optional<int> code = server.exit_code(kStartLimit);
    ASSERT_TRUE(code.has_value()) << argument << ": umbra_server kept running";
    EXPECT_EQ(*code, 1) << argument;
    EXPECT_NE(log_text(log).find(expected), std::string::npos) << argument << ":\n" << log_text(log);
  }
}

TEST_F(Loopback, SharedThreeDtkScans) {
  UMBRA_REQUIRE_SHARED_DATA(graph, "3dtk/3dtk_registered.graph");
  const double resolution = 0.2;
  const std::vector<RosScan> scans = file_scans(graph.string());
  ASSERT_FALSE(scans.empty());
  ASSERT_NO_FATAL_FAILURE(start_server(resolution, {"_integrator:=simple"}));
  ASSERT_NO_FATAL_FAILURE(publish(scans, 2000.0));
  const CommandResult built = run_command(std::string(UMBRA_CLI_PATH) + " build " + graph.string() +
                                          " --res 0.2 -o " + (dir_ / "3dtk.umb").string() + " 2>&1");
  ASSERT_EQ(built.exit_code, 0) << built.output;
  ASSERT_NO_FATAL_FAILURE(expect_published(load_map(dir_ / "3dtk.umb")));
}

/// A cloud in frame map (no transform needed) of FLOAT32 x, y, z (and an rgb field at `rgb_offset`, if given),
/// point_step 12: an rgb field there runs past the point.
sensor_msgs::PointCloud2 map_cloud(const std::vector<Vec3f>& points, const ros::Time& stamp,
                                   std::optional<std::uint32_t> rgb_offset = std::nullopt, bool with_z = true) {
  sensor_msgs::PointCloud2 cloud;
  cloud.header.frame_id = "map";
  cloud.header.stamp = stamp;
  std::vector<std::pair<std::string, std::uint32_t>> fields{{"x", 0}, {"y", 4}};
  if (with_z) fields.emplace_back("z", 8);
  if (rgb_offset) fields.emplace_back("rgb", *rgb_offset);
  for (const auto& [name, offset] : fields) {
    sensor_msgs::PointField field;
    field.name = name;
    field.offset = offset;
    field.datatype = sensor_msgs::PointField::FLOAT32;
    field.count = 1;
    cloud.fields.push_back(field);
  }
  cloud.height = 1;
  cloud.width = static_cast<std::uint32_t>(points.size());
  cloud.point_step = 12;
  cloud.row_step = 12 * cloud.width;
  cloud.data.resize(cloud.row_step);
  std::memcpy(cloud.data.data(), points.data(), cloud.data.size());  // Vec3f: three packed floats
  return cloud;
}

std::size_t occurrences(const std::string& text, const std::string& part) {
  std::size_t count = 0;
  for (std::size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + part.size())) ++count;
  return count;
}

// Issue 21, item 8: clouds the node used to refuse, to count wrongly, or to name twice in its error.
TEST_F(Loopback, HostileCloudsGiveAMapOrOneClearError) {
  ASSERT_NO_FATAL_FAILURE(start_server(0.1));
  const fs::path log = dir_ / "umbra_server.log";
  const std::vector<Vec3f> points{{1.0f, 1.0f, 1.0f}, {2.0f, 1.5f, 0.5f}, {-1.0f, 3.0f, 2.0f}};
  // An rgb field past point_step, colors off (~keep_colors false): not looked at, the cloud is mapped.
  EXPECT_TRUE(insert(map_cloud(points, ros::Time(5000.0), 12))) << log_text(log);
  // NaN points: skipped and counted in the log.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(insert(map_cloud({{nan, 0, 0}, {1.0f, 2.0f, 1.0f}, {0, nan, nan}}, ros::Time(5001.0))));
  EXPECT_NE(log_text(log).find("umbra_server: 2 of the 3 points of the cloud in frame 'map' at 5001.000000 are NaN or "
                               "infinite and were skipped"),
            std::string::npos)
      << log_text(log);
  // A malformed cloud: one error line that names the cloud once; the node goes on.
  EXPECT_FALSE(insert(map_cloud(points, ros::Time(5002.0), std::nullopt, false)));
  const std::string text = log_text(log);
  const std::size_t line_start = text.find("cannot insert the cloud in frame 'map' at 5002.000000");
  ASSERT_NE(line_start, std::string::npos) << text;
  const std::string line = text.substr(line_start, text.find('\n', line_start) - line_start);
  EXPECT_NE(line.find("at 5002.000000: PointCloud2 has no field z (fields: 'x', 'y')"), std::string::npos) << line;
  EXPECT_EQ(occurrences(line, "cloud in frame"), 1u) << line;
  EXPECT_TRUE(insert(map_cloud(points, ros::Time(5003.0)))) << log_text(log);
}

// Issue 21, item 1: the one-point cloud that ended a running node without a word (the fault was in the ray
// tracer, src/integrate): a map, and the node goes on. Were a library to crash the node again, its last line
// names the cloud (crash_log.hpp).
TEST_F(Loopback, OnePointOfTinyCoordinatesIsMapped) {
  ASSERT_NO_FATAL_FAILURE(start_server(0.1));
  const fs::path log = dir_ / "umbra_server.log";
  EXPECT_TRUE(insert(map_cloud({{1.0f, 1.0f, 1.0f}, {2.0f, -1.0f, 0.5f}}, ros::Time(5999.0)))) << log_text(log);
  EXPECT_TRUE(insert(map_cloud({{-1e-29f, 1e-29f, 0.0f}}, ros::Time(6000.0)))) << log_text(log);
  if (!server_->running()) {
    EXPECT_NE(log_text(log).find("[FATAL] umbra_server: stopped by "), std::string::npos) << log_text(log);
    EXPECT_NE(log_text(log).find(" while inserting the cloud in frame 'map' at 6000.000000"), std::string::npos);
  }
  ASSERT_TRUE(server_->running()) << log_text(log);
  EXPECT_TRUE(insert(map_cloud({{1.0f, 1.0f, 1.0f}}, ros::Time(6001.0)))) << log_text(log);
}

// --- depth images (issue 22) -----------------------------------------------------------------------------

const std::string kOpticalFrame = "camera_depth_optical_frame";

/// Where a camera's optical frame is, as TF carries it: a translation and a unit quaternion (w, x, y, z).
struct CameraPlacement {
  Vec3d position;
  double qw = 1.0;
  double qx = 0.0;
  double qy = 0.0;
  double qz = 0.0;

  /// The pose the node makes of the transform (the same function on the same numbers).
  [[nodiscard]] Pose pose() const {
    return Pose::from_translation_quaternion(position.x, position.y, position.z, qw, qx, qy, qz);
  }
  /// map -> the optical frame at `stamp`, on /tf.
  [[nodiscard]] tf2_msgs::TFMessage transform(const ros::Time& stamp) const {
    geometry_msgs::TransformStamped t;
    t.header.frame_id = "map";
    t.header.stamp = stamp;
    t.child_frame_id = kOpticalFrame;
    t.transform.translation.x = position.x;
    t.transform.translation.y = position.y;
    t.transform.translation.z = position.z;
    t.transform.rotation.w = qw;
    t.transform.rotation.x = qx;
    t.transform.rotation.y = qy;
    t.transform.rotation.z = qz;
    tf2_msgs::TFMessage message;
    message.transforms.push_back(t);
    return message;
  }
};

/// The placement of a rigid pose: its rotation as a quaternion (Shepperd's method, from the largest of w, x, y, z).
CameraPlacement placement_of(const Pose& pose) {
  const auto& m = pose.m;
  CameraPlacement p;
  p.position = pose.translation_d();
  const double trace = m[0][0] + m[1][1] + m[2][2];
  if (trace > 0.0) {
    const double s = 2.0 * std::sqrt(1.0 + trace);
    p.qw = s / 4.0;
    p.qx = (m[2][1] - m[1][2]) / s;
    p.qy = (m[0][2] - m[2][0]) / s;
    p.qz = (m[1][0] - m[0][1]) / s;
  } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]);
    p.qw = (m[2][1] - m[1][2]) / s;
    p.qx = s / 4.0;
    p.qy = (m[0][1] + m[1][0]) / s;
    p.qz = (m[0][2] + m[2][0]) / s;
  } else if (m[1][1] > m[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]);
    p.qw = (m[0][2] - m[2][0]) / s;
    p.qx = (m[0][1] + m[1][0]) / s;
    p.qy = s / 4.0;
    p.qz = (m[1][2] + m[2][1]) / s;
  } else {
    const double s = 2.0 * std::sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]);
    p.qw = (m[1][0] - m[0][1]) / s;
    p.qx = (m[0][2] + m[2][0]) / s;
    p.qy = (m[1][2] + m[2][1]) / s;
    p.qz = s / 4.0;
  }
  return p;
}

/// One depth image as a driver publishes it (16UC1 millimetres or 32FC1 metres) and as the library takes it.
struct CameraFrame {
  int width = 0;
  int height = 0;
  PinholeCamera camera;
  std::vector<std::uint16_t> millimetres;  ///< a 16UC1 frame (0: no reading)
  std::vector<float> metres;               ///< a 32FC1 frame (NaN: no reading)

  [[nodiscard]] DepthImage view() const {
    return millimetres.empty() ? DepthImage::metres(metres, width, height)
                               : DepthImage::raw(millimetres, width, height, 1000.0);
  }

  [[nodiscard]] sensor_msgs::Image image(const std::string& frame, const ros::Time& stamp) const {
    sensor_msgs::Image m;
    m.header.frame_id = frame;
    m.header.stamp = stamp;
    m.width = static_cast<std::uint32_t>(width);
    m.height = static_cast<std::uint32_t>(height);
    m.is_bigendian = 0;  // this machine's order, as drivers publish
    const bool raw = !millimetres.empty();
    m.encoding = raw ? "16UC1" : "32FC1";
    m.step = m.width * (raw ? 2u : 4u);
    m.data.resize(std::size_t{m.step} * m.height);
    std::memcpy(m.data.data(), raw ? static_cast<const void*>(millimetres.data()) : metres.data(), m.data.size());
    return m;
  }

  /// The calibration as a driver gives it: K and P (rectified: the same intrinsics), no distortion.
  [[nodiscard]] sensor_msgs::CameraInfo info(const std::string& frame, const ros::Time& stamp) const {
    sensor_msgs::CameraInfo m;
    m.header.frame_id = frame;
    m.header.stamp = stamp;
    m.width = static_cast<std::uint32_t>(width);
    m.height = static_cast<std::uint32_t>(height);
    m.distortion_model = "plumb_bob";
    m.D.assign(5, 0.0);
    m.K = {camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0};
    m.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
    m.P = {camera.fx, 0.0, camera.cx, 0.0, 0.0, camera.fy, camera.cy, 0.0, 0.0, 0.0, 1.0, 0.0};
    return m;
  }
};

/// 64 x 48 pixels of a flat wall 2 m ahead (16UC1), with no reading in the top-left 16 x 16 pixels.
CameraFrame wall_frame() {
  CameraFrame frame;
  frame.width = 64;
  frame.height = 48;
  frame.camera = PinholeCamera{50.0, 50.0, 31.5, 23.5};
  frame.millimetres.assign(64 * 48, 2000);
  for (int v = 0; v < 16; ++v) {
    for (int u = 0; u < 16; ++u) frame.millimetres[std::size_t(v * 64 + u)] = 0;
  }
  return frame;
}

/// A frame of the simulated depth camera in the office, in metres (NaN where nothing was seen) or millimetres.
CameraFrame office_frame(const sim::SimulatedDepthImage& simulated, bool millimetres) {
  CameraFrame frame;
  frame.width = simulated.width;
  frame.height = simulated.height;
  frame.camera = simulated.camera;
  for (const float z : simulated.depth) {
    if (millimetres) {
      frame.millimetres.push_back(static_cast<std::uint16_t>(std::lround(std::min(double(z) * 1000.0, 65535.0))));
    } else {
      frame.metres.push_back(z > 0.0f ? z : std::numeric_limits<float>::quiet_NaN());
    }
  }
  return frame;
}

sim::SimulatedDepthImage simulated_office_image(int pose_index) {
  sim::DepthCameraModel model = sim::noisy_depth_camera(7);
  model.width = 160;
  model.height = 60;
  return sim::simulate_depth_frame(sim::make_demo_scene(), sim::demo_camera_path()[std::size_t(pose_index)], model);
}

/// A color image registered to a width x height depth image (rgb8, or bgr8), and its colors for the library.
sensor_msgs::Image color_image(int width, int height, bool bgr, const ros::Time& stamp, std::vector<Rgb>& colors) {
  sensor_msgs::Image m;
  m.header.frame_id = "camera_color_optical_frame";  // ignored: the colors are the depth image's pixels'
  m.header.stamp = stamp;
  m.width = static_cast<std::uint32_t>(width);
  m.height = static_cast<std::uint32_t>(height);
  m.encoding = bgr ? "bgr8" : "rgb8";
  m.step = 3 * m.width;
  colors.clear();
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const Rgb c{static_cast<std::uint8_t>(4 * u), static_cast<std::uint8_t>(5 * v), static_cast<std::uint8_t>(200 - u)};
      colors.push_back(c);
      const std::array<std::uint8_t, 3> bytes = bgr ? std::array{c.b, c.g, c.r} : std::array{c.r, c.g, c.b};
      m.data.insert(m.data.end(), bytes.begin(), bytes.end());
    }
  }
  return m;
}

// Issue 22, item 5: depth images through ROS give the map the library makes of the same images (the
// projective integrator by default); the wall's map holds free space in front of it, the wall, and nothing
// known behind it or in front of the pixels without a reading.
TEST_F(Loopback, DepthImagesGiveTheLibrarysMap) {
  const double resolution = 0.1;
  ASSERT_NO_FATAL_FAILURE(start_server(resolution));
  const fs::path log = dir_ / "umbra_server.log";
  OccupancyMap expected(resolution, kOctoMapDepthLevels);
  InsertOptions options;
  options.integrator = IntegratorKind::projective;

  // The wall, 16UC1, from a camera looking along +x (optical z = map x, optical x = map -y, optical y = map -z).
  const CameraFrame wall = wall_frame();
  const CameraPlacement along_x{{1.02, 2.03, 1.47}, 0.5, -0.5, 0.5, -0.5};
  const ros::Time first(4000.0);
  publish_image_tf(along_x.transform(first));
  ASSERT_TRUE(insert_image(wall.image(kOpticalFrame, first), wall.info(kOpticalFrame, first))) << log_text(log);
  expected.insert_depth_image(wall.view(), wall.camera, along_x.pose(), {}, options);
  ASSERT_NO_FATAL_FAILURE(expect_published(expected));
  const OccupancyMap published = ros_io::map_from_message(*full_.get());
  EXPECT_EQ(published.state({2.02, 2.03, 1.47}), OccupancyState::free);      // 1 m in front of the wall
  EXPECT_EQ(published.state({3.02, 2.03, 1.47}), OccupancyState::occupied);  // the wall, 2 m ahead
  EXPECT_EQ(published.state({4.02, 2.03, 1.47}), OccupancyState::unknown);   // 1 m behind it
  // 1 m ahead, on the rays of pixel (8, 8), in the corner without readings, and of pixel (55, 39) opposite.
  EXPECT_EQ(published.state({2.02, 2.03 + 0.47, 1.47 + 0.31}), OccupancyState::unknown);
  EXPECT_EQ(published.state({2.02, 2.03 - 0.47, 1.47 - 0.31}), OccupancyState::free);

  // The simulated office, 32FC1 metres with NaN where nothing was seen, from a pose of its own.
  const sim::SimulatedDepthImage simulated = simulated_office_image(3);
  const CameraFrame office = office_frame(simulated, false);
  const CameraPlacement placement = placement_of(simulated.pose);
  const ros::Time second(4001.0);
  publish_image_tf(placement.transform(second));
  ASSERT_TRUE(insert_image(office.image(kOpticalFrame, second), office.info(kOpticalFrame, second))) << log_text(log);
  expected.insert_depth_image(office.view(), office.camera, placement.pose(), {}, options);
  ASSERT_NO_FATAL_FAILURE(expect_published(expected));

  // The wall again from elsewhere, as big-endian 16UC1 with rows padded by 6 bytes: read, not refused.
  const CameraPlacement lower{{0.52, 1.03, 1.21}, 0.5, -0.5, 0.5, -0.5};
  const ros::Time third(4002.0);
  publish_image_tf(lower.transform(third));
  const sensor_msgs::Image little = wall.image(kOpticalFrame, third);
  sensor_msgs::Image big = little;
  big.is_bigendian = 1;
  big.step = little.step + 6;
  big.data.assign(std::size_t{big.step} * big.height, 0xEE);
  for (std::size_t row = 0; row < big.height; ++row) {
    for (std::size_t byte = 0; byte < little.step; ++byte) {
      big.data[row * big.step + (byte ^ 1u)] = little.data[row * little.step + byte];  // swap each pixel's 2 bytes
    }
  }
  ASSERT_TRUE(insert_image(big, wall.info(kOpticalFrame, third))) << log_text(log);
  expected.insert_depth_image(wall.view(), wall.camera, lower.pose(), {}, options);
  ASSERT_NO_FATAL_FAILURE(expect_published(expected));

  // Not the map of the images' points inserted as clouds: the node read them as images.
  OccupancyMap as_points(resolution, kOctoMapDepthLevels);
  std::vector<Vec3f> points;
  back_project(wall.view(), wall.camera, along_x.pose(), points);
  as_points.insert_point_cloud(along_x.pose().translation(), points);
  back_project(office.view(), office.camera, placement.pose(), points);
  as_points.insert_point_cloud(placement.pose().translation(), points);
  back_project(wall.view(), wall.camera, lower.pose(), points);
  as_points.insert_point_cloud(lower.pose().translation(), points);
  EXPECT_NE(data_of(*full_.get()), tree_bytes(as_points, OctoMapFormat::ot));
}

// Color from a registered color image (~image_colors), and the image parameters reaching the integrator.
TEST_F(Loopback, ColorImagesAndImageParameters) {
  const double resolution = 0.1;
  ASSERT_NO_FATAL_FAILURE(start_server(resolution, {"rgb/image:=/camera/color/image_raw", "_keep_colors:=true",
                                                    "_image_colors:=true", "_image_max_range:=3.0",
                                                    "_surface_margin:=1.0"}));
  ASSERT_TRUE(wait_for([&] { return color_pub_.getNumSubscribers() > 0 || !server_->running(); }, kStartLimit));
  const fs::path log = dir_ / "umbra_server.log";
  MapConfig config;
  config.resolution = resolution;
  config.color = true;
  OccupancyMap expected(config);
  OccupancyMap with_defaults(config);  // the default range and margin
  InsertOptions options;
  options.integrator = IntegratorKind::projective;
  options.max_range = 3.0;
  options.surface_margin = 1.0;
  std::vector<Rgb> colors;

  const CameraFrame wall = wall_frame();
  const CameraPlacement along_x{{1.02, 2.03, 1.47}, 0.5, -0.5, 0.5, -0.5};
  const ros::Time first(4100.0);
  publish_image_tf(along_x.transform(first));
  const sensor_msgs::Image wall_colors = color_image(wall.width, wall.height, false, first, colors);
  ASSERT_TRUE(insert_image(wall.image(kOpticalFrame, first), wall.info(kOpticalFrame, first), &wall_colors))
      << log_text(log);
  expected.insert_depth_image(wall.view(), wall.camera, along_x.pose(), colors, options);
  with_defaults.insert_depth_image(wall.view(), wall.camera, along_x.pose(), colors);
  ASSERT_NO_FATAL_FAILURE(expect_published(expected));
  EXPECT_TRUE(expected.color(Vec3d{3.02, 2.03, 1.47}).has_value());  // the wall took the color image's colors

  // The office in 16UC1 millimetres, its colors as bgr8.
  const sim::SimulatedDepthImage simulated = simulated_office_image(5);
  const CameraFrame office = office_frame(simulated, true);
  const CameraPlacement placement = placement_of(simulated.pose);
  const ros::Time second(4101.0);
  publish_image_tf(placement.transform(second));
  const sensor_msgs::Image office_colors = color_image(office.width, office.height, true, second, colors);
  ASSERT_TRUE(insert_image(office.image(kOpticalFrame, second), office.info(kOpticalFrame, second), &office_colors))
      << log_text(log);
  expected.insert_depth_image(office.view(), office.camera, placement.pose(), colors, options);
  with_defaults.insert_depth_image(office.view(), office.camera, placement.pose(), colors);
  ASSERT_NO_FATAL_FAILURE(expect_published(expected));
  EXPECT_NE(data_of(*full_.get()), tree_bytes(with_defaults, OctoMapFormat::ot));
}

// Malformed images: one error line naming the image and the count of refused images; images tf2 cannot place
// or without a CameraInfo of their stamp: a warning naming the image and why; the node goes on mapping.
TEST_F(Loopback, MalformedDepthImagesAreRefusedAndTheNodeGoesOn) {
  // The images lie in frame map: a camera at the map's origin looking along z. A finite range, because the
  // projective integrator takes minutes for a camera whose image plane lies on the boundary of the map's
  // largest nodes when the range is unlimited (see docs/ros.md, "Depth images").
  ASSERT_NO_FATAL_FAILURE(start_server(0.1, {"_image_max_range:=10.0"}));
  const fs::path log = dir_ / "umbra_server.log";
  const CameraFrame wall = wall_frame();
  // The log line that starts with `start`, without roscpp's color codes around it.
  const auto line_of = [&](const std::string& start) {
    const std::string text = log_text(log);
    const std::size_t at = text.find(start);
    return at == std::string::npos ? std::string("(no line '" + start + "' in:\n" + text + ")")
                                   : text.substr(at, text.find_first_of("\n\x1B", at) - at);
  };

  // Frame map: no transform needed.
  sensor_msgs::Image bad_encoding = wall.image("map", ros::Time(7000.0));
  bad_encoding.encoding = "8UC1";
  EXPECT_FALSE(insert_image(bad_encoding, wall.info("map", ros::Time(7000.0))));
  EXPECT_EQ(line_of("umbra_server: cannot insert the depth image in frame 'map' at 7000.000000"),
            "umbra_server: cannot insert the depth image in frame 'map' at 7000.000000: depth image has encoding "
            "'8UC1'; umbra reads 16UC1 (millimetres) and 32FC1 (metres) (depth images refused so far: 1 of 1)");

  sensor_msgs::CameraInfo other_size = wall.info("map", ros::Time(7001.0));
  other_size.width = 640;
  other_size.height = 480;
  EXPECT_FALSE(insert_image(wall.image("map", ros::Time(7001.0)), other_size));
  EXPECT_EQ(line_of("umbra_server: cannot insert the depth image in frame 'map' at 7001.000000"),
            "umbra_server: cannot insert the depth image in frame 'map' at 7001.000000: depth image is 64 x 48 pixels, "
            "but its CameraInfo describes 640 x 480 (depth images refused so far: 2 of 2)");

  sensor_msgs::Image short_data = wall.image("map", ros::Time(7002.0));
  short_data.data.resize(100);
  EXPECT_FALSE(insert_image(short_data, wall.info("map", ros::Time(7002.0))));
  EXPECT_EQ(line_of("umbra_server: cannot insert the depth image in frame 'map' at 7002.000000"),
            "umbra_server: cannot insert the depth image in frame 'map' at 7002.000000: depth image (16UC1, 64 x 48) "
            "holds 100 bytes of data, but 48 rows of step 128 need 6144 (depth images refused so far: 3 of 3)");

  // A driver without calibration publishes a CameraInfo of zeros.
  sensor_msgs::CameraInfo uncalibrated;
  uncalibrated.header = wall.info("map", ros::Time(7003.0)).header;
  uncalibrated.width = 64;
  uncalibrated.height = 48;
  EXPECT_FALSE(insert_image(wall.image("map", ros::Time(7003.0)), uncalibrated));
  EXPECT_EQ(line_of("umbra_server: cannot insert the depth image in frame 'map' at 7003.000000"),
            "umbra_server: cannot insert the depth image in frame 'map' at 7003.000000: its CameraInfo has no "
            "calibration (fx 0.000000, fy 0.000000 from K; both must be > 0) (depth images refused so far: 4 of 4)");

  // An image without its CameraInfo: dropped with a warning once a newer image is matched.
  depth_pub_.publish(wall.image("map", ros::Time(7004.0)));
  EXPECT_TRUE(insert_image(wall.image("map", ros::Time(7005.0)), wall.info("map", ros::Time(7005.0))))
      << log_text(log);
  EXPECT_TRUE(wait_for([&] { return log_text(log).find("at 7004.000000") != std::string::npos; }, kMessageLimit));
  EXPECT_EQ(line_of("umbra_server: dropped the depth image in frame 'map' at 7004.000000"),
            "umbra_server: dropped the depth image in frame 'map' at 7004.000000: no CameraInfo with its stamp came on "
            "'/camera/depth/camera_info' (depth images refused so far: 5 of 6)");

  // A frame TF never names: each image is held for its transform until 5 newer ones push it out, then a warning
  // (one every 5 s; the count says how many). Published one by one: the subscriber's own queue is 5 deep too.
  const std::string no_transform = "tf2 had no transform from its frame to the map frame at its stamp";
  int published = 0;
  EXPECT_TRUE(wait_for(
      [&] {
        if (log_text(log).find("dropped the depth image in frame 'nowhere'") != std::string::npos) return true;
        if (published < 1000) depth_pub_.publish(wall.image("nowhere", ros::Time(7006.0 + 0.01 * published++)));
        return false;
      },
      kMessageLimit))
      << log_text(log);
  const std::string dropped = line_of("umbra_server: dropped the depth image in frame 'nowhere' at ");
  EXPECT_NE(dropped.find(": " + no_transform + " (depth images refused so far: 6 of "), std::string::npos) << dropped;
  EXPECT_GE(published, 6);

  // And the node still maps a good image.
  ASSERT_TRUE(server_->running()) << log_text(log);
  EXPECT_TRUE(insert_image(wall.image("map", ros::Time(7020.0)), wall.info("map", ros::Time(7020.0))))
      << log_text(log);
}

const auto* const kRosMaster = ::testing::AddGlobalTestEnvironment(new RosMaster);

}  // namespace
}  // namespace umbra::test
