// Backend selection: the status line, `auto` falling back to the CPU with a
// message, `cuda` refusing to run without a device, and parsing.
#include <gtest/gtest.h>

#include <string>

#include "gpu_test_support.h"
#include "lodestone/core/base/error.h"
#include "lodestone/gpu/backend.h"

using namespace lodestone;
using namespace lodestone::gpu;

TEST(GpuBackend, StatusMatchesTheBuildAndTheDevice) {
  const std::string s = backendStatus();
  if (!cudaBuilt()) {
    EXPECT_EQ(s, "not built");
    EXPECT_FALSE(deviceAvailable());
  } else if (deviceAvailable()) {
    EXPECT_EQ(s.rfind("device ", 0), 0u) << s;
  } else {
    EXPECT_EQ(s.rfind("built, no device", 0), 0u) << s;
  }
  std::printf("backendStatus(): %s\n", s.c_str());
}

TEST(GpuBackend, AutoFallsBackToTheCpuWithAMessage) {
  std::string message = "stale";
  const Backend b = resolveBackend(Backend::Auto, &message);
  if (deviceAvailable()) {
    EXPECT_EQ(b, Backend::Cuda);
    EXPECT_TRUE(message.empty());
  } else {
    EXPECT_EQ(b, Backend::Cpu);
    EXPECT_NE(message.find(backendStatus()), std::string::npos) << message;
    EXPECT_NE(message.find("CPU"), std::string::npos) << message;
  }
  EXPECT_EQ(resolveBackend(Backend::Cpu, &message), Backend::Cpu);
  EXPECT_TRUE(message.empty());
}

TEST(GpuBackend, CudaWithoutADeviceThrowsWithTheStatus) {
  if (deviceAvailable()) {
    EXPECT_EQ(resolveBackend(Backend::Cuda), Backend::Cuda);
    return;
  }
  try {
    resolveBackend(Backend::Cuda);
    FAIL() << "expected lodestone::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(backendStatus()), std::string::npos) << e.what();
  }
}

TEST(GpuBackend, ParsesItsNames) {
  for (Backend b : {Backend::Cpu, Backend::Cuda, Backend::Auto}) EXPECT_EQ(parseBackend(toString(b)), b);
  try {
    parseBackend("gpu0");
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("gpu0"), std::string::npos) << e.what();
  }
}
