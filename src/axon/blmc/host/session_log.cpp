#include "axon/blmc/host/session_log.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>

namespace axon::blmc::host {

Board::FrameTap candump_tap(can::CandumpWriter& writer, std::string iface, std::uint64_t* written) {
  return [&writer, iface = std::move(iface), written](const can::Frame& f, bool) {
    can::Frame g = f;
    if (g.timestamp().count() == 0) g.set_timestamp(core::SteadyClock::instance().wall());
    if (writer.write(g, iface) && written) ++*written;
  };
}

Result<CycleCsv> CycleCsv::create(const std::filesystem::path& path, std::size_t board) {
  if (board >= kMaxBoards) return Error(CoreErrc::invalid_argument, fmt::format("{}: no board {}", path.string(), board));
  CycleCsv csv;
  csv.file_.reset(std::fopen(path.c_str(), "w"));
  if (!csv.file_) return Error(CoreErrc::io, fmt::format("{}: {}", path.string(), std::strerror(errno)));
  csv.path_ = path;
  csv.board_ = board;
  if (std::fputs("cycle,t_s,current1_a,current2_a,position1_rev,position2_rev,velocity1_krpm,velocity2_krpm,"
                 "adc1,adc2,command1_a,command2_a,status\n",
                 csv.file_.get()) < 0)
    return Error(CoreErrc::io, fmt::format("{}: {}", path.string(), std::strerror(errno)));
  return csv;
}

bool CycleCsv::write(const CycleRecord& r) noexcept {
  if (!ok_) return false;
  if (lines_ == 0) t0_ = r.start;
  const auto& b = r.board[board_];
  const double t = std::chrono::duration<double>(r.start - t0_).count();
  ok_ = std::fprintf(file_.get(), "%llu,%.6f,%.5f,%.5f,%.6f,%.6f,%.5f,%.5f,%.4f,%.4f,%.5f,%.5f,%u\n",
                     static_cast<unsigned long long>(r.cycle), t, b.current.motor1, b.current.motor2, b.position.motor1,
                     b.position.motor2, b.velocity.motor1, b.velocity.motor2, b.adc.motor1, b.adc.motor2,
                     b.command.motor1, b.command.motor2, static_cast<unsigned>(b.status)) > 0;
  if (ok_) ++lines_;
  return ok_;
}

Result<void> CycleCsv::flush() {
  if (!ok_ || std::fflush(file_.get()) != 0)
    return Error(CoreErrc::io, fmt::format("{}: write failed after {} lines", path_.string(), lines_));
  return ok();
}

}  // namespace axon::blmc::host
