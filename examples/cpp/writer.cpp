// A mapping-stack-style writer: builds a small office (2 rooms, 4 objects with meshes)
// through the C++ wrapper, then at 30 Hz appends an agent pose (odometry edge, nested in
// its room), sways object 1000's mesh and, once a second, adds a newly detected object;
// each tick publishes only the layers that changed. Serves until SIGINT/SIGTERM.
//
// Layer names follow Spark-DSG's (ROOMS, OBJECTS, MESH, AGENTS), so the object queries
// (ygg query --scene, the Rust readers) answer on this scene too.
//
// Run: build/writer SCENE
#include <yggdrasil.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

namespace {
constexpr ygg::NodeId kRoom1 = 1, kRoom2 = 2;  // x in [0, 10) and [10, 20), y in [0, 8]
constexpr ygg::NodeId kFirstObject = 1000, kMeshOffset = 1000, kFirstPose = 1000000;
const char* const kLabels[] = {"chair", "table", "plant", "lamp"};

/// 8 mesh vertices: a 0.4 m cube around `c`.
std::vector<ygg::Point> cube(ygg::Point c, float dx = 0.0f) {
  std::vector<ygg::Point> v;
  for (int i = 0; i < 8; ++i) {
    v.push_back({c[0] + dx + ((i & 1) ? 0.2f : -0.2f), c[1] + ((i & 2) ? 0.2f : -0.2f), c[2] + ((i & 4) ? 0.2f : -0.2f)});
  }
  return v;
}

ygg::NodeId room_at(float x) { return x < 10.0f ? kRoom1 : kRoom2; }

/// An object with its mesh node, nested in the room under it.
void add_object(ygg::SceneGraph& g, ygg::NodeId id, const char* label, ygg::Point c) {
  g.add_node(id, g.layer_id("OBJECTS"));
  g.add_label(id, label);
  g.enable_bounding_box(id);
  g.nest(room_at(c[0]), id);
  g.add_node(id + kMeshOffset, g.layer_id("MESH"));
  g.set_geometry(id + kMeshOffset, cube(c));
  g.nest(id, id + kMeshOffset);
}

ygg::SceneGraph build_office() {
  ygg::SceneGraph g;
  auto rooms = g.add_layer("ROOMS"), objects = g.add_layer("OBJECTS");
  auto mesh = g.add_layer("MESH"), agents = g.add_layer("AGENTS");
  g.add_layer_edge(rooms, objects);
  g.add_layer_edge(objects, mesh);
  g.add_layer_edge(rooms, agents);
  for (auto room : {kRoom1, kRoom2}) {
    g.add_node(room, rooms);
    g.enable_bounding_box(room);
    g.set_feature(room, "name", room == kRoom1 ? "office" : "kitchen");
  }
  for (int i = 0; i < 4; ++i) add_object(g, kFirstObject + i, kLabels[i], {2.0f + 4.0f * i, 2.0f, 0.5f});
  g.enable_layer_index(mesh);
  return g;
}
}  // namespace

int main(int argc, char** argv) try {
  const std::string scene = argc > 1 ? argv[1] : "office-cpp";
  ygg::Writer writer(scene, build_office());
  writer.publish();
  std::printf("serving scene=%s nodes=%zu; Ctrl-C to stop\n", scene.c_str(), writer.graph().node_count());
  std::fflush(stdout);
  // ---- the mapping-stack loop ----
  const auto period = std::chrono::nanoseconds(33333333);  // 30 Hz
  const ygg::LayerId agents = writer.graph().layer_id("AGENTS");
  auto next = std::chrono::steady_clock::now();
  ygg::NodeId next_object = kFirstObject + 4;
  bool running = true;
  for (std::uint64_t tick = 0; running; ++tick) {
    ygg::SceneGraph& g = writer.graph();
    // The agent's new pose: walking along the corridor y = 4, back and forth.
    const float x = 1.0f + std::fabs(std::fmod(tick * 0.05f, 36.0f) - 18.0f);
    const ygg::NodeId pose = kFirstPose + tick;
    g.add_node(pose, agents);
    g.set_point(pose, {x, 4.0f, 1.0f});
    g.set_feature(pose, "stamp_ns", static_cast<std::int64_t>(tick * period.count()));
    if (tick > 0) g.add_edge(pose - 1, pose, "odometry");
    g.nest(room_at(x), pose);
    // Object 1000 sways by up to 10 cm along x (its box and the mesh index follow).
    g.set_geometry(kFirstObject + kMeshOffset, cube({2.0f, 2.0f, 0.5f}, 0.1f * std::sin(tick * 0.1f)));
    // Once a second, a newly detected box near the agent (at most 50).
    if (tick % 30 == 29 && next_object < kFirstObject + 54) {
      add_object(g, next_object++, "box", {x, 6.0f, 0.5f});
    }
    const ygg_publish_report report = writer.publish();  // the changed layers only
    if (tick % 30 == 0) {
      std::printf("generation=%llu layers_sent=%zu bytes_sent=%zu\n", static_cast<unsigned long long>(report.generation),
                  report.layers_sent, report.bytes_sent);
      std::fflush(stdout);
    }
    next += period;
    running = writer.wait(next - std::chrono::steady_clock::now());  // false on SIGINT/SIGTERM
  }
  std::printf("stopped at generation=%llu\n", static_cast<unsigned long long>(writer.status().generation));
  return 0;
} catch (const ygg::Error& e) {
  std::fprintf(stderr, "writer: %s\n", e.what());
  return 1;
}
