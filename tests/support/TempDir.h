#pragma once
// A fresh, empty folder for the running test: <gtest's TempDir>/<suite>/<test name>.

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace rhot::test {

inline std::filesystem::path fresh_test_dir(const std::string& suite) {
  const std::filesystem::path d =
      std::filesystem::path(::testing::TempDir()) / suite / ::testing::UnitTest::GetInstance()->current_test_info()->name();
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

}  // namespace rhot::test
