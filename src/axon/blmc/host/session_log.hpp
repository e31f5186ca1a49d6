// Logs of a board session, written off the real-time thread:
//
//  * candump_tap(): a Board::FrameTap that writes every frame the board receives or sends to a
//    candump log (`axon blmc --log`, `axon blmc record`), stamped with the host's wall clock where
//    the transport gave the frame no time stamp.
//  * CycleCsv: one CSV line per control cycle (ControlHooks::record, MotorBoard's csv option):
//      cycle,t_s,current1_a,current2_a,position1_rev,position2_rev,velocity1_krpm,velocity2_krpm,
//      adc1,adc2,command1_a,command2_a,status
//    t_s counts from the first record written; status is the board's status byte.
#pragma once

#include "axon/blmc/host/board.hpp"
#include "axon/blmc/host/control_loop.hpp"
#include "axon/can/candump_log.hpp"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace axon::blmc::host {

// `writer` must outlive the tap (remove the tap first: Board::set_tap({})). `written`, when given,
// counts the lines that went out.
Board::FrameTap candump_tap(can::CandumpWriter& writer, std::string iface, std::uint64_t* written = nullptr);

class CycleCsv {
 public:
  // Creates (truncates) the file and writes the header. Errors: CoreErrc::io naming the file.
  static Result<CycleCsv> create(const std::filesystem::path& path, std::size_t board = 0);

  // One line for board `board` of the record; false once a write failed.
  bool write(const CycleRecord& record) noexcept;
  Result<void> flush();
  [[nodiscard]] std::uint64_t lines() const noexcept { return lines_; }

 private:
  struct Close {
    void operator()(std::FILE* f) const noexcept { std::fclose(f); }
  };
  std::unique_ptr<std::FILE, Close> file_;
  std::filesystem::path path_;
  std::size_t board_ = 0;
  core::TimePoint t0_{};
  std::uint64_t lines_ = 0;
  bool ok_ = true;
};

}  // namespace axon::blmc::host
