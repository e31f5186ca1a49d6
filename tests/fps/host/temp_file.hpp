// A test fixture with one scratch file in the temporary folder, removed after the test.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace axon::fps::host::testing {

class TempFileTest : public ::testing::Test {
 protected:
  // Writes `text` to the scratch file and returns its path.
  std::string write(const std::string& text) {
    std::ofstream(path_) << text;
    return path_;
  }
  void TearDown() override { std::filesystem::remove(path_); }

 private:
  std::string path_ = (std::filesystem::temp_directory_path() /
                       (::testing::UnitTest::GetInstance()->current_test_info()->name() + std::string("-") +
                        std::to_string(::getpid()) + ".yaml"))
                          .string();
};

}  // namespace axon::fps::host::testing
