// A planner-style reader: for each new snapshot, the newest agent pose and its room
// (ygg_dsg::layout through the C API), the object nearest to it and the objects within
// 2 m, answered in place on the shared-memory bytes; stops after COUNT snapshots (default 30; 0 = until SIGINT/SIGTERM).
//
// Run the writer first, then: build/reader SCENE [COUNT]
#include <yggdrasil.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv) try {
  const std::string scene = argc > 1 ? argv[1] : "office-cpp";
  const long count = argc > 2 ? std::strtol(argv[2], nullptr, 10) : 30;
  ygg::Reader reader(scene, std::chrono::seconds(5), false, /*handle_termination_signals=*/true);
  for (long seen = 0; count == 0 || seen < count; ++seen) {
    std::optional<ygg::Snapshot> snapshot = reader.wait_next(std::chrono::seconds(2));
    if (!snapshot) {
      if (reader.termination_requested()) break;
      std::printf("no new snapshot (writer %s)\n", reader.writer_status() == YGG_WRITER_STATE_GONE ? "gone" : "alive");
      continue;
    }
    const std::optional<ygg::AgentPose> pose = snapshot->newest_pose();  // the AGENTS layer's newest
    if (!pose) {
      std::printf("generation=%llu no agent pose yet\n", static_cast<unsigned long long>(snapshot->generation()));
      continue;
    }
    const ygg::Point p{pose->position[0], pose->position[1], pose->position[2]};
    const auto room = snapshot->room_of(p);  // the ROOMS node whose box holds it
    const auto nearest = snapshot->nearest_object(p);
    const auto within = snapshot->objects_within(p, 2.0f);
    std::string ids;
    for (auto id : within) ids += (ids.empty() ? "" : ",") + std::to_string(id);
    std::printf("generation=%llu pose=%llu at=%.2f,%.2f,%.2f room=%s nearest=%s within=%zu ids=%s boxes=%zu\n",
                static_cast<unsigned long long>(snapshot->generation()), static_cast<unsigned long long>(pose->node), p[0], p[1],
                p[2], room ? std::to_string(*room).c_str() : "none",
                nearest ? std::to_string(*nearest).c_str() : "none", within.size(), ids.empty() ? "none" : ids.c_str(),
                snapshot->objects_with_label("box").size());
    std::fflush(stdout);
  }
  return 0;
} catch (const ygg::Error& e) {
  std::fprintf(stderr, "reader: %s\n", e.what());
  return 1;
}
