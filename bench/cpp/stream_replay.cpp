// The C++ side of `ygg-bench capi`: imports the office (Spark-DSG JSON, mint layout)
// through the C API, creates a writer, then replays the recorded SLAM-style stream
// (bench/src/capi/trace.rs has the format) through the C++ wrapper, timing each tick's
// mutations and its publish; then times tight loops of single mutation calls on a node of a layer of its own.
//
// Usage: stream_replay OFFICE_JSON TRACE SCENE BATCHES
// Prints `tick I EDITS MUTATION_NS PUBLISH_NS` per tick and
// `micro NAME NS_PER_CALL` per batch of 1000 calls.
#include <yggdrasil.hpp>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {
struct Edit {
  std::uint8_t op = 0;
  std::uint64_t a = 0, b = 0;  // node (or source / parent), and target / child
  std::uint32_t layer = 0;
  std::vector<float> xyz;
  std::string key, text;  // key; label, description or string value
  std::uint8_t kind = 0;
  std::int64_t int_value = 0;
  double float_value = 0.0;
};

struct Cursor {
  const std::vector<char>& bytes;
  std::size_t at = 0;
  template <typename T>
  T get() {
    T v;
    std::memcpy(&v, bytes.data() + at, sizeof v);
    at += sizeof v;
    return v;
  }
  std::string str() {
    auto n = get<std::uint32_t>();
    std::string s(bytes.data() + at, n);
    at += n;
    return s;
  }
};

std::vector<std::vector<Edit>> read_trace(const char* path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Cursor c{bytes};
  std::vector<std::vector<Edit>> ticks(c.get<std::uint32_t>());
  for (auto& tick : ticks) {
    tick.resize(c.get<std::uint32_t>());
    for (Edit& e : tick) {
      e.op = c.get<std::uint8_t>();
      e.a = c.get<std::uint64_t>();
      switch (e.op) {
        case 0: e.layer = c.get<std::uint32_t>(); break;
        case 1:
        case 6: {
          e.xyz.resize(3 * std::size_t{c.get<std::uint32_t>()});
          for (float& v : e.xyz) v = c.get<float>();
          break;
        }
        case 2:
          e.key = c.str();
          e.kind = c.get<std::uint8_t>();
          if (e.kind == 0) e.text = c.str();
          if (e.kind == 1) e.int_value = c.get<std::int64_t>();
          if (e.kind == 2) e.float_value = c.get<double>();
          if (e.kind == 3) e.int_value = c.get<std::uint8_t>();
          break;
        case 3: e.text = c.str(); break;
        case 4: e.b = c.get<std::uint64_t>(); e.text = c.str(); break;
        case 5: e.b = c.get<std::uint64_t>(); break;
      }
    }
  }
  return ticks;
}

void apply(ygg::SceneGraph& g, const Edit& e) {
  switch (e.op) {
    case 0: g.add_node(e.a, e.layer); break;
    case 1: g.set_geometry(e.a, e.xyz.data(), e.xyz.size() / 3); break;
    case 2:
      if (e.kind == 0) g.set_feature(e.a, e.key, e.text);
      if (e.kind == 1) g.set_feature(e.a, e.key, e.int_value);
      if (e.kind == 2) g.set_feature(e.a, e.key, e.float_value);
      if (e.kind == 3) g.set_feature(e.a, e.key, e.int_value != 0);
      break;
    case 3: g.add_label(e.a, e.text); break;
    case 4: g.add_edge(e.a, e.b, e.text); break;
    case 5: g.nest(e.a, e.b); break;
    case 6: g.append_points(e.a, e.xyz.data(), e.xyz.size() / 3); break;
  }
}

std::int64_t since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t).count();
}
}  // namespace

int main(int argc, char** argv) try {
  if (argc != 5) {
    std::fprintf(stderr, "usage: stream_replay OFFICE_JSON TRACE SCENE BATCHES\n");
    return 2;
  }
  const auto ticks = read_trace(argv[2]);
  const int batches = std::stoi(argv[4]);
  ygg::Writer writer(argv[3], ygg::SceneGraph::import_dsg(argv[1], "mint"));
  writer.publish();
  ygg::SceneGraph& g = writer.graph();
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    auto t0 = std::chrono::steady_clock::now();
    for (const Edit& e : ticks[i]) apply(g, e);
    const std::int64_t mutation = since(t0);
    auto t1 = std::chrono::steady_clock::now();
    writer.publish();
    std::printf("tick %zu %zu %lld %lld\n", i, ticks[i].size(), static_cast<long long>(mutation),
                static_cast<long long>(since(t1)));
  }
  // The single-call loops' node: in a layer of its own (as on the Rust side).
  const ygg::NodeId micro_node = UINT64_MAX - 1;
  g.add_node(micro_node, g.add_layer("micro"));
  const std::string key = "tick";
  for (int b = 0; b < batches; ++b) {
    auto t = std::chrono::steady_clock::now();
    for (std::int64_t i = 0; i < 1000; ++i) g.set_feature(micro_node, key, i);
    std::printf("micro set_feature_int %.2f\n", since(t) / 1000.0);
    t = std::chrono::steady_clock::now();
    for (int i = 0; i < 1000; ++i) g.set_point(micro_node, {static_cast<float>(i), 1.0f, 1.0f});
    std::printf("micro set_geometry_1 %.2f\n", since(t) / 1000.0);
  }
  return 0;
} catch (const ygg::Error& e) {
  std::fprintf(stderr, "stream_replay: %s\n", e.what());
  return 1;
}
