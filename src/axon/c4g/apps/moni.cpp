#include "axon/c4g/apps/moni.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <cstring>
#include <iterator>

namespace axon::c4g::apps {

namespace {

constexpr std::array<MoniColumn, 6> kType19{{{"pc_d1", true, 1}, {"pc_d2", true, 2}, {"pc_d3", true, 3},
                                             {"pc_d4", true, 4}, {"pc_d5", true, 5}, {"mode", false, 0}}};
constexpr std::array<MoniColumn, 6> kType20{{{"c4g_d1", false, 1}, {"c4g_d2", false, 2}, {"c4g_d3", false, 3},
                                             {"c4g_d4", false, 4}, {"c4g_d5", false, 5}, {"mode", false, 0}}};
constexpr std::array<MoniColumn, 6> kType21{{{"pc_d1", true, 1}, {"pc_d2", true, 2}, {"c4g_d1", false, 1},
                                             {"c4g_d3", false, 3}, {"c4g_d5", false, 5}, {"mode", false, 0}}};
constexpr std::array<MoniColumn, 6> kType22{{{"pc_d4", true, 4}, {"pc_d5", true, 5}, {"c4g_d1", false, 1},
                                             {"c4g_d3", false, 3}, {"c4g_d5", false, 5}, {"mode", false, 0}}};
constexpr std::array<MoniColumn, 6> kType23{{{"c4g_d1", false, 1}, {"c4g_d5", false, 5}, {"c4g_ext1", false, 6},
                                             {"c4g_ext2", false, 7}, {"pc_d5", true, 5}, {"mode", false, 0}}};
constexpr std::array<MoniColumn, 6> kType24{{{"c4g_d1", false, 1}, {"c4g_d5", false, 5}, {"c4g_ext1", false, 6},
                                             {"c4g_ext2", false, 7}, {"pc_d4", true, 4}, {"mode", false, 0}}};
constexpr std::array<MoniColumn, 18> kAll{{{"c4g_sm", false, 0},   {"c4g_d1", false, 1},  {"c4g_d2", false, 2},
                                           {"c4g_d3", false, 3},   {"c4g_d4", false, 4},  {"c4g_d5", false, 5},
                                           {"c4g_ext1", false, 6}, {"c4g_ext2", false, 7}, {"c4g_ext3", false, 8},
                                           {"pc_sm", true, 0},     {"pc_d1", true, 1},    {"pc_d2", true, 2},
                                           {"pc_d3", true, 3},     {"pc_d4", true, 4},    {"pc_d5", true, 5},
                                           {"pc_ext1", true, 6},   {"pc_ext2", true, 7},  {"pc_ext3", true, 8}}};

double field_value(const protocol::Axis& a, int field) noexcept {
  switch (field) {
    case 0: return a.mode;
    case 1: return a.d1;
    case 2: return a.d2;
    case 3: return a.d3;
    case 4: return a.d4;
    case 5: return a.d5;
    case 6: return a.ext1;
    case 7: return a.ext2;
    case 8: return a.ext3;
    default: return 0;
  }
}

}  // namespace

bool is_moni_type(int type) noexcept { return type == 0 || (type >= 19 && type <= 24); }

std::span<const MoniColumn> moni_columns(int type) noexcept {
  switch (type) {
    case 0: return kAll;
    case 19: return kType19;
    case 20: return kType20;
    case 21: return kType21;
    case 22: return kType22;
    case 23: return kType23;
    case 24: return kType24;
    default: return {};
  }
}

std::string moni_header(int type, std::size_t axes) {
  std::string out = type == 0 ? "cycle,time_s,c4g_num,c4g_infpar,c4g_cmd,pc_num,pc_infpar,pc_cmd" : "cycle,time_s";
  for (std::size_t a = 0; a < axes; ++a)
    for (const auto& c : moni_columns(type)) out += fmt::format(",a{}_{}", a + 1, c.name);
  out += '\n';
  return out;
}

void append_moni_row(std::string& out, int type, std::uint64_t cycle, double time_s, const protocol::Packet& c4g,
                     const protocol::Packet& pc) {
  auto it = std::back_inserter(out);
  fmt::format_to(it, "{},{:.6f}", cycle, time_s);
  if (type == 0) fmt::format_to(it, ",{},{},{},{},{},{}", c4g.num, c4g.infpar, c4g.cmd, pc.num, pc.infpar, pc.cmd);
  for (std::size_t a = 0; a < c4g.count; ++a) {
    for (const auto& c : moni_columns(type)) {
      const auto& packet = c.from_pc ? pc : c4g;
      const double v = a < packet.count ? field_value(packet.axes[a], c.field) : 0.0;
      if (c.field == 0) fmt::format_to(it, ",{}", static_cast<long>(v));
      else fmt::format_to(it, ",{:.9g}", v);
    }
  }
  out += '\n';
}

Result<std::unique_ptr<MoniCsvWriter>> MoniCsvWriter::open(const std::string& path, int type, core::RotationLimits rotation) {
  if (!is_moni_type(type))
    return Error(CoreErrc::invalid_argument, fmt::format("moni type {} unknown (19..24, or 0 for every field)", type));
  std::unique_ptr<MoniCsvWriter> w(new MoniCsvWriter());
  auto f = core::RotatingFile::open(path, rotation, core::steady_now());
  if (!f) return Error(CoreErrc::invalid_argument, f.error().detail);
  w->file_.emplace(std::move(f).value());
  w->path_ = path;
  w->type_ = type;
  return w;
}

MoniCsvWriter::~MoniCsvWriter() { flush(); }

void MoniCsvWriter::write(std::uint64_t cycle, std::int64_t wall_ns, const protocol::Packet& c4g, const protocol::Packet& pc) {
  if (rows_ == 0) {
    axes_ = c4g.count;
    t0_ = wall_ns;
    line_.clear();
    line_ += moni_header(type_, axes_);
    (void)file_->set_header(line_);
  }
  if (c4g.count != axes_) return;  // another configuration (restart): keep the file rectangular
  line_.clear();
  append_moni_row(line_, type_, cycle, static_cast<double>(wall_ns - t0_) * 1e-9, c4g, pc);
  ++rows_;
  if (auto r = file_->write(line_, core::steady_now()); !r && write_errors_++ == 0)
    spdlog::error("csv {}: {} (further errors only counted)", path_, r.error().detail);
}

void MoniCsvWriter::flush() {
  if (file_) (void)file_->flush();
}

}  // namespace axon::c4g::apps
