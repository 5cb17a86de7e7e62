// The Slurm integration test, and a worked example of running purkinje on
// Slurm. It starts a single-node Slurm cluster of its own from Debian's
// packages (munged, slurmctld and slurmd, configured in a temporary folder:
// no system-wide configuration is read or touched), then does what
// examples/slurm/README.md tells users to do:
//
//   sbatch --array=0-3 examples/slurm/generate.sbatch SPEC OUT --count 8
//   sbatch --dependency=afterok:JOBID --wrap "purkinje merge OUT"
//
// and checks that OUT holds, byte for byte, what one unsharded
// `purkinje generate SPEC -o DIR --count 8` writes, plus the shards' own
// tables and manifests.
//
// Without the packages (bash scripts/install-deps.sh installs them) the test
// is skipped, or fails when the environment variable CI is set. It runs as
// root or as any other user: the daemons run as whoever runs the test.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <pwd.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

const fs::path kPurkinje = PURKINJE_EXECUTABLE;
const fs::path kSourceDir = PURKINJE_SOURCE_DIR;
const fs::path kExampleScript = kSourceDir / "examples/slurm/generate.sbatch";
const fs::path kSpec = kSourceDir / "assets/datasets/remote.json";
constexpr int kShards = 4;
constexpr int kImages = 8;

// ---------------------------------------------------------------------------
// Running programs

// The full path of a program: on PATH, or in the sbin folders a user's PATH
// often lacks (munged, slurmctld and slurmd live in /usr/sbin). Empty if none.
fs::path find_program(const std::string& name) {
  std::string path = std::getenv("PATH") ? std::getenv("PATH") : "";
  path += ":/usr/sbin:/sbin";
  std::istringstream folders(path);
  for (std::string folder; std::getline(folders, folder, ':');) {
    if (folder.empty()) continue;
    const fs::path candidate = fs::path(folder) / name;
    if (::access(candidate.c_str(), X_OK) == 0 && fs::is_regular_file(candidate)) return candidate;
  }
  return {};
}

// A child's argv or environment as execve wants it (built before fork).
struct CStrings {
  explicit CStrings(const std::vector<std::string>& strings) {
    for (const std::string& s : strings) pointers.push_back(const_cast<char*>(s.c_str()));
    pointers.push_back(nullptr);
  }
  std::vector<char*> pointers;
};

// Forks and runs `command` (command[0] a full path) with `environment`, its
// standard output and error on `output_fd`. The child dies with the test
// (PR_SET_PDEATHSIG), so a test killed by CTest's timeout leaves no daemon.
pid_t spawn(const std::vector<std::string>& command, const std::vector<std::string>& environment,
            int output_fd) {
  CStrings argv(command);
  CStrings envp(environment);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    const int null = ::open("/dev/null", O_RDONLY);
    ::dup2(null, STDIN_FILENO);
    ::dup2(output_fd, STDOUT_FILENO);
    ::dup2(output_fd, STDERR_FILENO);
    ::execve(argv.pointers[0], argv.pointers.data(), envp.pointers.data());
    ::_exit(127);
  }
  return pid;
}

struct Result {
  int exit_code = -1;  // -1: killed, or did not start
  std::string output;  // standard output and error
};

// Runs `command` to its end (killed after `timeout`).
Result run(const std::vector<std::string>& command, const std::vector<std::string>& environment,
           std::chrono::seconds timeout = 120s) {
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) return {-1, "pipe2 failed"};
  const pid_t pid = spawn(command, environment, pipe_fds[1]);
  ::close(pipe_fds[1]);
  Result result;
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left <= 0ms) {
      ::kill(pid, SIGKILL);
      result.output += "\n(killed after " + std::to_string(timeout.count()) + " s)";
      break;
    }
    pollfd readable{pipe_fds[0], POLLIN, 0};
    if (::poll(&readable, 1, static_cast<int>(left.count())) <= 0) continue;
    char buffer[4096];
    const ssize_t n = ::read(pipe_fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    result.output.append(buffer, static_cast<size_t>(n));
  }
  ::close(pipe_fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  return result;
}

// Single quotes for the shell; a quote inside becomes '\''.
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_file(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

// A TCP port nobody listens on now, so the test's cluster can run beside a
// real Slurm (ports 6817 and 6818) and beside another run of this test.
int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof address;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), size) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size) != 0) {
    ::close(fd);
    return -1;
  }
  ::close(fd);
  return ntohs(address.sin_port);
}

// The job id `sbatch --parsable` prints ("JOBID" or "JOBID;CLUSTER"), on
// the first line that starts with a digit (warnings may come first).
std::string job_id_in(const std::string& sbatch_output) {
  std::istringstream lines(sbatch_output);
  for (std::string line; std::getline(lines, line);) {
    if (!line.empty() && std::isdigit(static_cast<unsigned char>(line[0]))) return line.substr(0, line.find(';'));
  }
  return {};
}

// Regular files under `folder`, by path relative to it.
std::set<std::string> files_in(const fs::path& folder) {
  std::set<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    if (entry.is_regular_file()) names.insert(fs::relative(entry.path(), folder).string());
  }
  return names;
}

std::string seconds_since(Clock::time_point start) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f s", std::chrono::duration<double>(Clock::now() - start).count());
  return text;
}

// ---------------------------------------------------------------------------
// The cluster

// A single-node Slurm cluster in a temporary folder:
//
//   ROOT/slurm.conf   the configuration every daemon and command reads (SLURM_CONF)
//   ROOT/munge/       munged's key, socket, pid and seed files
//   ROOT/state/       slurmctld's saved state
//   ROOT/spool/       slurmd's spool
//   ROOT/log/         the daemons' logs and the jobs' output
//
// SetUp starts munged, slurmctld and slurmd and waits for the node to be
// idle; TearDown cancels any job left, stops the daemons (also after a
// failure), prints the logs if the test failed, and removes ROOT.
class SlurmCluster : public ::testing::Test {
 protected:
  void SetUp() override {
    // The packages: munge, slurmctld, slurmd, slurm-client.
    std::string missing;
    for (const char* name : {"munged", "mungekey", "slurmctld", "slurmd", "sbatch", "sinfo", "squeue", "scancel"}) {
      programs_[name] = find_program(name);
      if (programs_[name].empty()) missing += std::string(missing.empty() ? "" : ", ") + name;
    }
    if (!missing.empty()) {
      const std::string message = "Slurm is not installed (missing " + missing +
                                  "): run `bash scripts/install-deps.sh` to install munge, slurmctld, "
                                  "slurmd and slurm-client";
      const char* ci = std::getenv("CI");
      if (ci != nullptr && *ci != '\0') FAIL() << message << " (CI is set, so this fails rather than skips)";
      GTEST_SKIP() << message;
    }

    ASSERT_NO_FATAL_FAILURE(make_root());
    conf_ = root_ / "slurm.conf";
    environment_ = environment_for_slurm();
    user_ = user_name();
    host_ = short_host_name();
    slurmctld_port_ = free_port();
    do slurmd_port_ = free_port();
    while (slurmd_port_ == slurmctld_port_);
    write_file(conf_, slurm_conf());

    // munged: a key of its own (a cluster's nodes share one key; this one
    // has a single node). Slurm finds the socket through AuthInfo.
    const fs::path munge = root_ / "munge";
    const Result key = run({programs_["mungekey"], "--create", "--keyfile=" + (munge / "munge.key").string()},
                           environment_);
    ASSERT_EQ(key.exit_code, 0) << key.output;
    start("munged", {programs_["munged"], "--foreground", "--socket=" + (munge / "socket").string(),
                     "--key-file=" + (munge / "munge.key").string(),
                     "--pid-file=" + (munge / "munged.pid").string(),
                     "--seed-file=" + (munge / "munged.seed").string(),
                     "--log-file=" + (munge / "munged.log").string()});
    ASSERT_NO_FATAL_FAILURE(wait_until("munged's socket", 20s, [&] { return fs::exists(munge / "socket"); }));

    // The controller (-i: no saved state to recover) and the node's daemon,
    // both in the foreground so that the test owns their processes.
    start("slurmctld", {programs_["slurmctld"], "-D", "-i", "-f", conf_.string()});
    start("slurmd", {programs_["slurmd"], "-D", "-f", conf_.string(), "-N", host_});
    const auto start_time = Clock::now();
    ASSERT_NO_FATAL_FAILURE(wait_until("the node to be idle", 90s, [&] {
      return slurm({"sinfo", "--noheader", "--Node", "--format=%t"}, 10s).output == "idle\n";
    }));
    std::cout << "[ slurm    ] node " << host_ << " idle after " << seconds_since(start_time) << "\n";
    cluster_up_ = true;
  }

  void TearDown() override {
    if (cluster_up_) {  // no job may outlive the cluster
      slurm({"scancel", "--user=" + user_}, 30s);
      const auto deadline = Clock::now() + 60s;
      while (Clock::now() < deadline && !slurm({"squeue", "--noheader"}, 10s).output.empty()) {
        std::this_thread::sleep_for(500ms);
      }
    }
    for (auto daemon = daemons_.rbegin(); daemon != daemons_.rend(); ++daemon) stop(*daemon);
    if (HasFailure() && !root_.empty()) print_logs();
    if (!root_.empty()) {
      std::error_code ignored;
      fs::remove_all(root_, ignored);
    }
  }

  // Runs a Slurm command (sbatch, sinfo, ...) against this cluster.
  Result slurm(std::vector<std::string> command, std::chrono::seconds timeout = 120s,
               const std::vector<std::string>& more_environment = {}) {
    command[0] = programs_[command[0]].string();
    std::vector<std::string> environment = environment_;
    environment.insert(environment.end(), more_environment.begin(), more_environment.end());
    return run(command, environment, timeout);
  }

  fs::path root_;
  std::vector<std::string> environment_;  // the test's, for Slurm's commands and jobs

 private:
  struct Daemon {
    std::string name;
    pid_t pid;
  };

  // ROOT, in /tmp rather than TMPDIR: every folder on the way to munged's
  // socket must be searchable by all (munged insists), and a socket's path
  // must be short (108 bytes).
  void make_root() {
    std::string pattern = "/tmp/purkinje-slurm-XXXXXX";
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr) << "mkdtemp " << pattern << ": " << std::strerror(errno);
    root_ = pattern;
    for (const char* folder : {"munge", "state", "spool", "log"}) fs::create_directories(root_ / folder);
    for (const fs::path& folder : {root_, root_ / "munge"}) {
      fs::permissions(folder, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                                  fs::perms::others_read | fs::perms::others_exec);
    }
  }

  // The test's environment without anything that would steer Slurm's
  // commands elsewhere (SBATCH_PARTITION, SQUEUE_FORMAT, the SLURM_* of an
  // enclosing job, ...) or the example script (SPEC, OUT, SHARDS,
  // PURKINJE), plus SLURM_CONF.
  std::vector<std::string> environment_for_slurm() const {
    std::vector<std::string> environment;
    for (char** variable = environ; *variable != nullptr; ++variable) {
      const std::string entry = *variable;
      const std::string name = entry.substr(0, entry.find('='));
      bool drop = name == "SPEC" || name == "OUT" || name == "SHARDS" || name == "PURKINJE";
      for (const char* prefix : {"SLURM_", "SBATCH_", "SALLOC_", "SRUN_", "SQUEUE_", "SINFO_", "SCANCEL_"}) {
        drop = drop || name.rfind(prefix, 0) == 0;
      }
      if (!drop) environment.push_back(entry);
    }
    environment.push_back("SLURM_CONF=" + conf_.string());
    return environment;
  }

  static std::string user_name() {
    const passwd* user = ::getpwuid(::geteuid());
    return user != nullptr ? user->pw_name : std::to_string(::geteuid());
  }

  // slurmctld checks it runs on SlurmctldHost by this name.
  static std::string short_host_name() {
    char name[256] = {};
    ::gethostname(name, sizeof name - 1);
    const std::string host = name;
    return host.substr(0, host.find('.'));
  }

  // The minimal configuration: this host as controller and only node with
  // its CPUs (those this process may run on) and memory (as slurmd counts
  // it: more than it finds would drain the node), one partition, no
  // accounting database, no cgroups, the daemons and jobs run as the user
  // running the test (root or not), everything under ROOT.
  std::string slurm_conf() const {
    cpu_set_t cpus;
    CPU_ZERO(&cpus);
    ::sched_getaffinity(0, sizeof cpus, &cpus);
    const long memory_mb = ::sysconf(_SC_PHYS_PAGES) * (::sysconf(_SC_PAGESIZE) / 1024) / 1024;
    const std::string root = root_.string();
    std::ostringstream conf;
    conf << "ClusterName=purkinje-test\n"
         << "SlurmctldHost=" << host_ << "(127.0.0.1)\n"
         << "SlurmctldPort=" << slurmctld_port_ << "\n"
         << "SlurmdPort=" << slurmd_port_ << "\n"
         << "SlurmUser=" << user_ << "\n"
         << "SlurmdUser=" << user_ << "\n"
         << "AuthType=auth/munge\n"
         << "CredType=cred/munge\n"
         << "AuthInfo=socket=" << root << "/munge/socket\n"
         << "StateSaveLocation=" << root << "/state\n"
         << "SlurmdSpoolDir=" << root << "/spool\n"
         << "SlurmctldPidFile=" << root << "/slurmctld.pid\n"
         << "SlurmdPidFile=" << root << "/slurmd.pid\n"
         << "ProctrackType=proctrack/linuxproc\n"
         << "TaskPlugin=task/none\n"
         << "JobAcctGatherType=jobacct_gather/none\n"
         << "AccountingStorageType=accounting_storage/none\n"
         << "JobCompType=jobcomp/none\n"
         << "SelectType=select/cons_tres\n"
         << "SelectTypeParameters=CR_CPU\n"
         << "MpiDefault=none\n"
         << "MailProg=/bin/true\n"  // the default, /bin/mail, is seldom installed
         << "NodeName=" << host_ << " NodeAddr=127.0.0.1 CPUs=" << CPU_COUNT(&cpus)
         << " RealMemory=" << memory_mb << " State=UNKNOWN\n"
         << "PartitionName=test Nodes=" << host_ << " Default=YES MaxTime=INFINITE State=UP\n";
    return conf.str();
  }

  void start(const std::string& name, const std::vector<std::string>& command) {
    const fs::path log = root_ / "log" / (name + ".log");  // in the foreground they log to stderr
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    daemons_.push_back({name, spawn(command, environment_, fd)});
    ::close(fd);
  }

  // Polls `ready` every half second; fails if a daemon exits meanwhile.
  template <class Ready>
  void wait_until(const std::string& what, std::chrono::seconds timeout, Ready ready) {
    const auto deadline = Clock::now() + timeout;
    while (!ready()) {
      for (Daemon& daemon : daemons_) {
        int status = 0;
        if (daemon.pid > 0 && ::waitpid(daemon.pid, &status, WNOHANG) == daemon.pid) {
          daemon.pid = -1;
          FAIL() << daemon.name << " exited while waiting for " << what << " (status " << status << ")";
        }
      }
      if (Clock::now() > deadline) FAIL() << "gave up waiting for " << what << " after " << timeout.count() << " s";
      std::this_thread::sleep_for(500ms);
    }
  }

  // SIGTERM, then SIGKILL if it has not exited within 30 s.
  static void stop(Daemon& daemon) {
    if (daemon.pid <= 0) return;
    ::kill(daemon.pid, SIGTERM);
    const auto deadline = Clock::now() + 30s;
    while (::waitpid(daemon.pid, nullptr, WNOHANG) == 0) {
      if (Clock::now() > deadline) {
        std::cerr << daemon.name << " (pid " << daemon.pid << ") ignored SIGTERM for 30 s; killed\n";
        ::kill(daemon.pid, SIGKILL);
        ::waitpid(daemon.pid, nullptr, 0);
        break;
      }
      std::this_thread::sleep_for(100ms);
    }
    daemon.pid = -1;
  }

  void print_logs() const {
    std::cerr << "--- " << conf_.string() << "\n" << read_file(conf_);
    std::error_code ignored;
    for (const auto& entry : fs::directory_iterator(root_ / "log", ignored)) {
      const std::string text = read_file(entry.path());
      const size_t tail = text.size() > 4000 ? text.size() - 4000 : 0;
      std::cerr << "--- " << entry.path().string() << (tail > 0 ? " (its end)" : "") << "\n" << text.substr(tail);
    }
  }

  std::map<std::string, fs::path> programs_;
  fs::path conf_;
  std::string user_;
  std::string host_;
  int slurmctld_port_ = 0;
  int slurmd_port_ = 0;
  std::vector<Daemon> daemons_;
  bool cluster_up_ = false;
};

// ---------------------------------------------------------------------------
// The test

TEST_F(SlurmCluster, JobArrayOfShardsMergesIntoTheUnshardedSet) {
  const fs::path sharded = root_ / "sharded";
  const fs::path unsharded = root_ / "unsharded";
  const std::string job_output = (root_ / "log" / "%x-%A_%a.out").string();  // not in the data set's folder

  // The shards: one array task each, all writing into one folder, with the
  // example script as users submit it. The command line overrides three of
  // its #SBATCH lines: 4 tasks instead of 100, 1 CPU per task instead of 4
  // (this node may have only 2), and the tasks' output in ROOT/log. --wait
  // returns when every task has ended, with the highest of their exit codes.
  auto start_time = Clock::now();
  const Result array = slurm({"sbatch", "--parsable", "--wait", "--array=0-" + std::to_string(kShards - 1),
                              "--cpus-per-task=1", "--output=" + job_output, "--chdir=" + root_.string(),
                              kExampleScript.string(), kSpec.string(), sharded.string(), "--count",
                              std::to_string(kImages)},
                             240s, {"PURKINJE=" + kPurkinje.string()});
  ASSERT_EQ(array.exit_code, 0) << "sbatch --array (the tasks' output is among the logs below): " << array.output;
  const std::string job_id = job_id_in(array.output);
  ASSERT_FALSE(job_id.empty()) << array.output;
  std::cout << "[ slurm    ] job array " << job_id << " done after " << seconds_since(start_time) << "\n";

  // The merge, as a job that starts once every task has succeeded (on a
  // cluster one submits both at once; here the array has already ended).
  start_time = Clock::now();
  const Result merge =
      slurm({"sbatch", "--parsable", "--wait", "--dependency=afterok:" + job_id, "--job-name=purkinje-merge",
             "--output=" + job_output, "--chdir=" + root_.string(),
             "--wrap=" + quoted(kPurkinje.string()) + " merge " + quoted(sharded.string())},
            90s);
  ASSERT_EQ(merge.exit_code, 0) << "sbatch merge: " << merge.output;
  std::cout << "[ slurm    ] merge job done after " << seconds_since(start_time) << "\n";

  // The same set in one run, without Slurm.
  const Result one_run = run({kPurkinje.string(), "generate", kSpec.string(), "-o", unsharded.string(), "--count",
                              std::to_string(kImages), "--quiet"},
                             environment_, 120s);
  ASSERT_EQ(one_run.exit_code, 0) << one_run.output;

  // Every file of the unsharded run, with the same bytes...
  const std::set<std::string> expected = files_in(unsharded);
  std::set<std::string> found = files_in(sharded);
  ASSERT_TRUE(expected.count("table.csv") && expected.count("manifest.json"));
  for (const std::string& name : expected) {
    if (!found.count(name)) {
      ADD_FAILURE() << name << " is missing from the merged shards";
      continue;
    }
    EXPECT_TRUE(read_file(unsharded / name) == read_file(sharded / name))
        << name << " differs between the merged shards and the unsharded run";
    found.erase(name);
  }
  // ... and besides them only the shards' own tables and manifests.
  std::set<std::string> shard_files;
  for (int i = 0; i < kShards; ++i) {
    const std::string suffix = ".shard-" + std::to_string(i) + "-of-" + std::to_string(kShards);
    shard_files.insert("table" + suffix + ".csv");
    shard_files.insert("manifest" + suffix + ".json");
  }
  EXPECT_EQ(found, shard_files);
}

}  // namespace
