#include "axon/fps/host/datum_check.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <vector>

namespace axon::fps::host {

namespace asio = boost::asio;

asio::awaitable<Result<std::vector<plan::Pose>>> read_poses_around(Array& array, const plan::CollisionModel& model,
                                                                   std::size_t index, const std::string& what) {
  std::vector<plan::Pose> poses(model.size());
  std::vector<std::size_t> read{index};
  for (const auto j : model.neighbours(index)) read.push_back(j);
  for (const auto j : read) {
    const auto rid = static_cast<std::uint16_t>(model.robot(j).id());
    auto p = array.positioner(rid);
    if (!p) co_return p.error();
    auto pos = co_await p.value()->read_position();
    if (!pos)
      co_return Error(HostErrc::not_ready,
                      fmt::format("{} refused: the position of {} is unknown ({}), so its way cannot be proven clear", what,
                                  j == index ? "the robot itself" : fmt::format("neighbour {}", rid), pos.error().message()));
    poses[j] = {pos.value().alpha, pos.value().beta};
  }
  co_return poses;
}

asio::awaitable<Result<plan::StopSweep>> check_datum_sweep(Array& array, const plan::CollisionModel& model,
                                                           std::uint16_t id, Arm arm) {
  // A locked array refuses the datum anyway, with its own reason: say that, not what is in the way.
  if (auto admitted = array.admit_all(protocol::CommandId::go_to_datums, {id}); !admitted) co_return admitted.error();
  const auto index = model.index_of(id);
  if (!index) co_return Error(HostErrc::unknown_positioner, fmt::format("robot {} is not in the layout", id));
  auto read = co_await read_poses_around(array, model, *index, fmt::format("datum search of robot {}", id));
  if (!read) co_return read.error();
  const auto& poses = read.value();
  plan::StopSweepOptions o;
  o.alpha = arm != Arm::beta;
  o.beta = arm != Arm::alpha;
  auto sweep = plan::check_sweep_to_stops(model, *index, poses, o);
  if (!sweep.clear)
    co_return Error(HostErrc::not_ready,
                    fmt::format("datum search of robot {} ({}) refused: driving to the hard stops from alpha {:.1f} beta "
                                "{:.1f} may touch {}; move them away first",
                                id, to_string(arm), poses[*index].alpha_deg, poses[*index].beta_deg,
                                fmt::join(sweep.in_the_way, ", ")));
  co_return sweep;
}

}  // namespace axon::fps::host
