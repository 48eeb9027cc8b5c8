// Yggdrasil C++17 wrapper: header-only RAII classes over the C API (yggdrasil.h).
//
//   ygg::SceneGraph  a graph being built (owned), or a writer's live graph (borrowed)
//   ygg::Writer      publishes a graph through shared memory
//   ygg::Reader      attaches to a scene, receives snapshots
//   ygg::Snapshot    a validated, immutable cut: node accessors and the paper's queries
//
// Every failing C call throws ygg::Error carrying the status and the library's message.
// Classes are move-only; destructors release the handle and never throw. Points are
// returned as ygg::Points, a span-like view into the snapshot's mapped bytes, valid while
// the Snapshot lives. Thread-safety is the C API's: SceneGraph, Writer and Reader from one
// thread at a time; a Snapshot from any number of threads at once.
#ifndef YGGDRASIL_HPP
#define YGGDRASIL_HPP

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "yggdrasil.h"

namespace ygg {

/// A failed call: the status code and the library's message.
class Error : public std::runtime_error {
public:
  Error(ygg_status status, const std::string& message) : std::runtime_error(message), status_(status) {}
  /// The C API's status code.
  ygg_status status() const noexcept { return status_; }

private:
  ygg_status status_;
};

/// Throws Error for anything but YGG_STATUS_OK.
inline void check(ygg_status status) {
  if (status != YGG_STATUS_OK) {
    throw Error(status, ygg_last_error());
  }
}

using NodeId = std::uint64_t;
using LayerId = std::uint32_t;
/// The layer argument of a query that means every layer.
constexpr LayerId kAllLayers = YGG_ALL_LAYERS;

/// A point: x, y, z (metres).
using Point = std::array<float, 3>;

/// A read-only, span-like view of points (x y z floats, contiguous) in a snapshot's
/// bytes. Valid while the Snapshot it came from lives.
class Points {
public:
  Points() = default;
  Points(const float* xyz, std::size_t count) : xyz_(xyz), count_(count) {}
  /// Number of points.
  std::size_t size() const noexcept { return count_; }
  bool empty() const noexcept { return count_ == 0; }
  /// The floats, 3 per point (null when empty).
  const float* data() const noexcept { return xyz_; }
  /// Point number i (not bounds-checked).
  Point operator[](std::size_t i) const noexcept { return {xyz_[3 * i], xyz_[3 * i + 1], xyz_[3 * i + 2]}; }

  /// A random-access iterator over the points (yields Point by value).
  class iterator {
  public:
    using iterator_category = std::random_access_iterator_tag;
    using value_type = Point;
    using difference_type = std::ptrdiff_t;
    using pointer = void;
    using reference = Point;
    iterator(const float* p) : p_(p) {}
    Point operator*() const noexcept { return {p_[0], p_[1], p_[2]}; }
    iterator& operator++() noexcept { p_ += 3; return *this; }
    iterator operator++(int) noexcept { iterator t = *this; p_ += 3; return t; }
    iterator& operator+=(difference_type n) noexcept { p_ += 3 * n; return *this; }
    difference_type operator-(const iterator& o) const noexcept { return (p_ - o.p_) / 3; }
    bool operator==(const iterator& o) const noexcept { return p_ == o.p_; }
    bool operator!=(const iterator& o) const noexcept { return p_ != o.p_; }

  private:
    const float* p_;
  };
  iterator begin() const noexcept { return iterator(xyz_); }
  iterator end() const noexcept { return iterator(xyz_ + 3 * count_); }

private:
  const float* xyz_ = nullptr;
  std::size_t count_ = 0;
};

/// The newest agent pose: node, position, previous position, unit heading (x y z each).
using AgentPose = ygg_agent_pose;
/// Where a room's objects live in a per-room layout: its claimed-mesh layer and group node.
using RoomScope = ygg_room_scope;

/// Sets how much the shared-memory transport prints on stderr, process-wide: "trace",
/// "debug", "info", "warn", "error" (the default unless the environment variable YGG_LOG
/// names another level) or "fatal". Throws Error for any other name.
inline void set_log_level(const std::string& level) { check(ygg_set_log_level(level.c_str())); }

/// A node of a ranked answer: id and distance (metres).
struct Ranked {
  NodeId id;
  float distance;
};

namespace detail {
/// Takes the ids of a C list and frees it.
inline std::vector<NodeId> take_ids(ygg_node_list& list) {
  std::vector<NodeId> out(list.ids, list.ids + list.len);
  ygg_node_list_free(&list);
  return out;
}
/// Takes the ranked ids of a C list and frees it.
inline std::vector<Ranked> take_ranked(ygg_node_list& list) {
  std::vector<Ranked> out;
  out.reserve(list.len);
  for (std::size_t i = 0; i < list.len; ++i) {
    out.push_back({list.ids[i], list.distances[i]});
  }
  ygg_node_list_free(&list);
  return out;
}
/// Runs a list-filling C call and converts the list with `take`; frees it whatever
/// happens.
template <typename Call, typename Take>
inline auto run_list(Call call, Take take) {
  ygg_node_list list{nullptr, nullptr, 0};
  ygg_status status = call(&list);
  if (status != YGG_STATUS_OK) {
    ygg_node_list_free(&list);
    check(status);
  }
  return take(list);
}
template <typename Call>
inline std::vector<NodeId> ids(Call call) {
  return run_list(call, take_ids);
}
template <typename Call>
inline std::vector<Ranked> ranked(Call call) {
  return run_list(call, take_ranked);
}
}  // namespace detail

class Writer;
class Snapshot;

/// A scene graph: owned (SceneGraph(), SceneGraph::import_dsg) or a writer's live graph
/// (Writer::graph(), borrowed: it goes with the writer). Every mutation either applies
/// fully or throws, leaving the graph unchanged.
class SceneGraph {
public:
  /// An empty graph.
  SceneGraph() { check(ygg_graph_create(&handle_)); }
  /// Imports a Spark-DSG file into one of the paper's layouts ("vanilla", "chocolate",
  /// "mint", "saffron").
  static SceneGraph import_dsg(const std::string& path, const std::string& layout = "mint", bool lenient = false) {
    ygg_graph* g = nullptr;
    check(ygg_graph_import_dsg(path.c_str(), layout.c_str(), lenient, &g));
    return SceneGraph(g, true);
  }
  ~SceneGraph() { reset(); }
  SceneGraph(SceneGraph&& o) noexcept : handle_(std::exchange(o.handle_, nullptr)), owned_(o.owned_) {}
  SceneGraph& operator=(SceneGraph&& o) noexcept {
    if (this != &o) {
      reset();
      handle_ = std::exchange(o.handle_, nullptr);
      owned_ = o.owned_;
    }
    return *this;
  }
  SceneGraph(const SceneGraph&) = delete;
  SceneGraph& operator=(const SceneGraph&) = delete;

  LayerId add_layer(const std::string& name) {
    LayerId id = 0;
    check(ygg_graph_add_layer(handle_, name.c_str(), &id));
    return id;
  }
  LayerId layer_id(const std::string& name) const {
    LayerId id = 0;
    check(ygg_graph_layer_id(handle_, name.c_str(), &id));
    return id;
  }
  void remove_layer(LayerId layer) { check(ygg_graph_remove_layer(handle_, layer)); }
  void add_layer_edge(LayerId parent, LayerId child) { check(ygg_graph_add_layer_edge(handle_, parent, child)); }
  void remove_layer_edge(LayerId parent, LayerId child) { check(ygg_graph_remove_layer_edge(handle_, parent, child)); }
  void add_node(NodeId node, LayerId layer) { check(ygg_graph_add_node(handle_, node, layer)); }
  void remove_node(NodeId node) { check(ygg_graph_remove_node(handle_, node)); }
  /// Sets a node's geometry from `count` points of x y z floats (copied).
  void set_geometry(NodeId node, const float* xyz, std::size_t count) {
    check(ygg_graph_set_geometry(handle_, node, xyz, count));
  }
  void set_geometry(NodeId node, const std::vector<Point>& points) {
    set_geometry(node, points.empty() ? nullptr : points.front().data(), points.size());
  }
  void set_point(NodeId node, Point p) { set_geometry(node, p.data(), 1); }
  /// Appends `count` points of x y z floats to a node's geometry (copied; a growing mesh).
  void append_points(NodeId node, const float* xyz, std::size_t count) {
    check(ygg_graph_append_points(handle_, node, xyz, count));
  }
  void append_points(NodeId node, const std::vector<Point>& points) {
    append_points(node, points.empty() ? nullptr : points.front().data(), points.size());
  }
  void set_feature(NodeId node, const std::string& key, const std::string& value) {
    check(ygg_graph_set_feature_str(handle_, node, key.c_str(), value.c_str()));
  }
  void set_feature(NodeId node, const std::string& key, const char* value) {
    check(ygg_graph_set_feature_str(handle_, node, key.c_str(), value));
  }
  void set_feature(NodeId node, const std::string& key, std::int64_t value) {
    check(ygg_graph_set_feature_int(handle_, node, key.c_str(), value));
  }
  void set_feature(NodeId node, const std::string& key, int value) { set_feature(node, key, std::int64_t{value}); }
  void set_feature(NodeId node, const std::string& key, double value) {
    check(ygg_graph_set_feature_float(handle_, node, key.c_str(), value));
  }
  void set_feature(NodeId node, const std::string& key, bool value) {
    check(ygg_graph_set_feature_bool(handle_, node, key.c_str(), value));
  }
  void remove_feature(NodeId node, const std::string& key) { check(ygg_graph_remove_feature(handle_, node, key.c_str())); }
  void add_label(NodeId node, const std::string& label) { check(ygg_graph_add_label(handle_, node, label.c_str())); }
  void remove_label(NodeId node, const std::string& label) { check(ygg_graph_remove_label(handle_, node, label.c_str())); }
  void add_edge(NodeId source, NodeId target, const std::string& description = "") {
    check(ygg_graph_add_edge(handle_, source, target, description.c_str()));
  }
  void remove_edge(NodeId source, NodeId target) { check(ygg_graph_remove_edge(handle_, source, target)); }
  void nest(NodeId parent, NodeId child) { check(ygg_graph_nest(handle_, parent, child)); }
  void unnest(NodeId child) { check(ygg_graph_unnest(handle_, child)); }
  void enable_bounding_box(NodeId node) { check(ygg_graph_enable_bounding_box(handle_, node)); }
  void disable_bounding_box(NodeId node) { check(ygg_graph_disable_bounding_box(handle_, node)); }
  void enable_layer_index(LayerId layer) { check(ygg_graph_enable_layer_index(handle_, layer)); }
  void disable_layer_index(LayerId layer) { check(ygg_graph_disable_layer_index(handle_, layer)); }
  void enable_node_index(NodeId node) { check(ygg_graph_enable_node_index(handle_, node)); }
  void disable_node_index(NodeId node) { check(ygg_graph_disable_node_index(handle_, node)); }
  std::size_t node_count() const {
    std::size_t n = 0;
    check(ygg_graph_node_count(handle_, &n));
    return n;
  }
  /// Writes a .ygg snapshot file.
  void save(const std::string& path) const { check(ygg_graph_save(handle_, path.c_str())); }
  /// Archives the graph into an in-memory snapshot (queried as a reader would).
  inline Snapshot snapshot() const;

  /// The C handle (still owned by this object).
  ygg_graph* handle() const noexcept { return handle_; }

private:
  friend class Writer;
  SceneGraph(ygg_graph* handle, bool owned) : handle_(handle), owned_(owned) {}
  void reset() noexcept {
    if (handle_ != nullptr && owned_) {
      ygg_graph_destroy(handle_);
    }
    handle_ = nullptr;
  }
  ygg_graph* handle_ = nullptr;
  bool owned_ = true;
};

/// A validated, immutable snapshot: node accessors (zero-copy) and the paper's queries.
class Snapshot {
public:
  /// Opens a .ygg snapshot file (mapped and validated once).
  static Snapshot open_file(const std::string& path) {
    ygg_snapshot* s = nullptr;
    check(ygg_snapshot_open_file(path.c_str(), &s));
    return Snapshot(s);
  }
  explicit Snapshot(ygg_snapshot* handle) noexcept : handle_(handle) {}
  ~Snapshot() { reset(); }
  Snapshot(Snapshot&& o) noexcept : handle_(std::exchange(o.handle_, nullptr)) {}
  Snapshot& operator=(Snapshot&& o) noexcept {
    if (this != &o) {
      reset();
      handle_ = std::exchange(o.handle_, nullptr);
    }
    return *this;
  }
  Snapshot(const Snapshot&) = delete;
  Snapshot& operator=(const Snapshot&) = delete;

  std::uint64_t generation() const {
    std::uint64_t g = 0;
    check(ygg_snapshot_generation(handle_, &g));
    return g;
  }
  std::size_t node_count() const {
    std::size_t n = 0;
    check(ygg_snapshot_node_count(handle_, &n));
    return n;
  }
  /// The layer named `name`, if any.
  std::optional<LayerId> layer_by_name(const std::string& name) const {
    LayerId id = 0;
    ygg_status s = ygg_snapshot_layer_by_name(handle_, name.c_str(), &id);
    if (s == YGG_STATUS_NOT_FOUND) return std::nullopt;
    check(s);
    return id;
  }
  std::vector<NodeId> layer_nodes(LayerId layer) const {
    return detail::ids([&](ygg_node_list* l) { return ygg_snapshot_layer_nodes(handle_, layer, l); });
  }

  // ---- node accessors (throw Error with YGG_STATUS_NOT_FOUND for an unknown node) ----
  LayerId layer_of(NodeId node) const {
    LayerId id = 0;
    check(ygg_snapshot_node_layer(handle_, node, &id));
    return id;
  }
  /// The node's points, zero-copy (valid while this snapshot lives).
  Points points(NodeId node) const {
    const float* xyz = nullptr;
    std::size_t n = 0;
    check(ygg_snapshot_node_points(handle_, node, &xyz, &n));
    return Points(xyz, n);
  }
  std::optional<NodeId> parent(NodeId node) const {
    bool has = false;
    NodeId p = 0;
    check(ygg_snapshot_node_parent(handle_, node, &has, &p));
    return has ? std::optional<NodeId>(p) : std::nullopt;
  }
  std::vector<NodeId> children(NodeId node) const {
    return detail::ids([&](ygg_node_list* l) { return ygg_snapshot_node_children(handle_, node, l); });
  }
  /// The node's box: min x y z, max x y z.
  std::optional<std::array<float, 6>> aabb(NodeId node) const {
    bool has = false;
    std::array<float, 6> b{};
    check(ygg_snapshot_node_aabb(handle_, node, &has, b.data()));
    return has ? std::optional<std::array<float, 6>>(b) : std::nullopt;
  }
  bool has_label(NodeId node, const std::string& label) const {
    bool has = false;
    check(ygg_snapshot_node_has_label(handle_, node, label.c_str(), &has));
    return has;
  }
  /// The node's labels (views into the snapshot's bytes).
  std::vector<std::string_view> labels(NodeId node) const {
    std::size_t n = 0;
    check(ygg_snapshot_node_label_count(handle_, node, &n));
    std::vector<std::string_view> out;
    for (std::size_t i = 0; i < n; ++i) {
      const char* p = nullptr;
      std::size_t len = 0;
      check(ygg_snapshot_node_label(handle_, node, i, &p, &len));
      out.emplace_back(p, len);
    }
    return out;
  }
  /// A node's feature, if it has the key.
  std::optional<ygg_feature> feature(NodeId node, const std::string& key) const {
    ygg_feature f{};
    ygg_status s = ygg_snapshot_node_feature(handle_, node, key.c_str(), &f);
    if (s == YGG_STATUS_NOT_FOUND) return std::nullopt;
    check(s);
    return f;
  }

  // ---- queries (the store's and the object contract's, run on the mapped bytes) ----
  std::vector<Ranked> nearest_nodes(Point c, std::size_t m, LayerId layer = kAllLayers) const {
    return detail::ranked([&](ygg_node_list* l) { return ygg_snapshot_nearest_nodes(handle_, layer, c.data(), m, l); });
  }
  std::vector<NodeId> nodes_within_radius(Point c, float r, LayerId layer = kAllLayers) const {
    return detail::ids([&](ygg_node_list* l) { return ygg_snapshot_nodes_within_radius(handle_, layer, c.data(), r, l); });
  }
  std::vector<Ranked> nearest_in_subtree(NodeId root, Point c, std::size_t m) const {
    return detail::ranked([&](ygg_node_list* l) { return ygg_snapshot_nearest_in_subtree(handle_, root, c.data(), m, l); });
  }
  std::vector<NodeId> visible(NodeId root, Point eye, Point dir, float half_angle_deg, float range) const {
    return detail::ids([&](ygg_node_list* l) {
      return ygg_snapshot_visible(handle_, root, eye.data(), dir.data(), half_angle_deg, range, l);
    });
  }
  std::vector<NodeId> nodes_with_label(const std::string& label, LayerId layer = kAllLayers) const {
    return detail::ids([&](ygg_node_list* l) { return ygg_snapshot_nodes_with_label(handle_, layer, label.c_str(), l); });
  }
  std::vector<NodeId> nodes_having(const std::vector<std::string>& keys, LayerId layer = kAllLayers) const {
    std::vector<const char*> c_keys;
    for (const auto& k : keys) c_keys.push_back(k.c_str());
    return detail::ids([&](ygg_node_list* l) {
      return ygg_snapshot_nodes_having(handle_, layer, c_keys.data(), c_keys.size(), l);
    });
  }
  std::vector<NodeId> subtree(NodeId root) const {
    return detail::ids([&](ygg_node_list* l) { return ygg_snapshot_subtree(handle_, root, l); });
  }
  /// Q1a: the object nearest to `c`.
  std::optional<NodeId> nearest_object(Point c) const {
    bool found = false;
    NodeId id = 0;
    check(ygg_snapshot_nearest_object(handle_, c.data(), &found, &id));
    return found ? std::optional<NodeId>(id) : std::nullopt;
  }
  /// Q1b: objects within `r` of `c`.
  std::vector<NodeId> objects_within(Point c, float r) const {
    return detail::ids([&](ygg_node_list* l) { return ygg_snapshot_objects_within(handle_, c.data(), r, l); });
  }
  /// Q2: objects in the view cone (half-angle in degrees).
  std::vector<NodeId> visible_objects(Point eye, Point dir, float half_angle_deg, float range) const {
    return detail::ids([&](ygg_node_list* l) {
      return ygg_snapshot_visible_objects(handle_, eye.data(), dir.data(), half_angle_deg, range, l);
    });
  }
  /// Q3: objects carrying `label`.
  std::vector<NodeId> objects_with_label(const std::string& label) const {
    return detail::ids([&](ygg_node_list* l) { return ygg_snapshot_objects_with_label(handle_, label.c_str(), l); });
  }

  // ---- where the agent is (ygg_dsg::layout; Spark-DSG layer names) ----
  /// The newest agent pose (the AGENTS layer's largest id with a point), if any.
  std::optional<AgentPose> newest_pose() const {
    bool found = false;
    AgentPose pose{};
    check(ygg_snapshot_newest_pose(handle_, &found, &pose));
    return found ? std::optional<AgentPose>(pose) : std::nullopt;
  }
  /// The room whose box holds `p` in x and y (the smallest id when several do), if any.
  std::optional<NodeId> room_of(Point p) const {
    bool found = false;
    NodeId room = 0;
    check(ygg_snapshot_room_of(handle_, p.data(), &found, &room));
    return found ? std::optional<NodeId>(room) : std::nullopt;
  }
  /// Where `room`'s objects live in a per-room layout (chocolate, mint, saffron), if it is one.
  std::optional<RoomScope> room_scope(NodeId room) const {
    bool found = false;
    RoomScope scope{};
    check(ygg_snapshot_room_scope(handle_, room, &found, &scope));
    return found ? std::optional<RoomScope>(scope) : std::nullopt;
  }
  /// The distinct parents of `nodes` (the objects owning mesh nodes), ascending.
  std::vector<NodeId> owners(const std::vector<NodeId>& nodes) const {
    return detail::ids([&](ygg_node_list* l) { return ygg_snapshot_owners(handle_, nodes.data(), nodes.size(), l); });
  }

  /// The C handle (still owned by this object).
  ygg_snapshot* handle() const noexcept { return handle_; }

private:
  void reset() noexcept {
    if (handle_ != nullptr) {
      ygg_snapshot_destroy(handle_);
    }
    handle_ = nullptr;
  }
  ygg_snapshot* handle_ = nullptr;
};

inline Snapshot SceneGraph::snapshot() const {
  ygg_snapshot* s = nullptr;
  check(ygg_graph_snapshot(handle_, &s));
  return Snapshot(s);
}

/// Publishes a scene graph through shared memory; destroying it removes the scene's
/// shared memory (readers keep their last snapshot and report the writer gone).
class Writer {
public:
  /// Creates the writer of `scene` and moves `graph` into it (`graph` is left empty).
  Writer(const std::string& scene, SceneGraph&& graph, ygg_writer_options options = {}) {
    check(ygg_writer_create(scene.c_str(), graph.handle_, &options, &handle_));
    graph.handle_ = nullptr;  // the C call destroyed the graph handle
    ygg_graph* live = nullptr;
    ygg_status status = ygg_writer_graph(handle_, &live);
    if (status != YGG_STATUS_OK) {
      ygg_writer_destroy(handle_);
      check(status);
    }
    graph_ = SceneGraph(live, false);
  }
  ~Writer() {
    graph_ = SceneGraph(nullptr, false);
    if (handle_ != nullptr) {
      ygg_writer_destroy(handle_);
    }
  }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// The live graph; mutations reach readers at the next publish().
  SceneGraph& graph() noexcept { return graph_; }
  /// Publishes every changed layer, then the manifest.
  ygg_publish_report publish() {
    ygg_publish_report report{};
    check(ygg_writer_publish(handle_, &report));
    return report;
  }
  ygg_writer_status_info status() const {
    ygg_writer_status_info s{};
    check(ygg_writer_status(handle_, &s));
    return s;
  }
  /// Sleeps up to `timeout`; returns false when SIGINT/SIGTERM asks the process to stop.
  bool wait(std::chrono::nanoseconds timeout) const {
    bool stop = false;
    check(ygg_writer_wait(handle_, timeout.count() > 0 ? static_cast<std::uint64_t>(timeout.count()) : 0, &stop));
    return !stop;
  }

private:
  ygg_writer* handle_ = nullptr;
  SceneGraph graph_{nullptr, false};
};

/// Attaches to a published scene and receives validated snapshots.
class Reader {
public:
  /// Attaches to `scene`, waiting up to `wait_for_writer` for its writer.
  explicit Reader(const std::string& scene, std::chrono::milliseconds wait_for_writer = std::chrono::milliseconds(0),
                  bool copy_segments = false, bool handle_termination_signals = false) {
    ygg_reader_options options{static_cast<std::uint64_t>(wait_for_writer.count()), copy_segments,
                               handle_termination_signals};
    check(ygg_reader_open(scene.c_str(), &options, &handle_));
  }
  ~Reader() {
    if (handle_ != nullptr) {
      ygg_reader_destroy(handle_);
    }
  }
  Reader(Reader&& o) noexcept : handle_(std::exchange(o.handle_, nullptr)) {}
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;
  Reader& operator=(Reader&&) = delete;

  /// The next snapshot newer than the current one, or nullopt after `timeout`.
  std::optional<Snapshot> wait_next(std::chrono::nanoseconds timeout) {
    ygg_snapshot* s = nullptr;
    check(ygg_reader_wait_next(handle_, static_cast<std::uint64_t>(timeout.count()), &s));
    return s ? std::optional<Snapshot>(Snapshot(s)) : std::nullopt;
  }
  /// The newest snapshot without blocking (nullopt before the first).
  std::optional<Snapshot> latest() {
    ygg_snapshot* s = nullptr;
    check(ygg_reader_latest(handle_, &s));
    return s ? std::optional<Snapshot>(Snapshot(s)) : std::nullopt;
  }
  ygg_writer_state writer_status() const {
    ygg_writer_state state = YGG_WRITER_STATE_UNKNOWN;
    check(ygg_reader_writer_status(handle_, &state));
    return state;
  }
  /// Whether SIGINT/SIGTERM arrived (with handle_termination_signals).
  bool termination_requested() const {
    bool requested = false;
    check(ygg_reader_termination_requested(handle_, &requested));
    return requested;
  }

private:
  ygg_reader* handle_ = nullptr;
};

/// A recording of a live scene (a folder written by `ygg record` or `Recorder`); any
/// recorded moment is a `Snapshot` queried in place on the mapped files.
class Recording {
public:
  /// Opens the recording in folder `path`; throws `Error` if it is not one.
  explicit Recording(const std::string& path) { check(ygg_recording_open(path.c_str(), &handle_)); }
  ~Recording() {
    if (handle_ != nullptr) {
      ygg_recording_destroy(handle_);
    }
  }
  Recording(Recording&& o) noexcept : handle_(std::exchange(o.handle_, nullptr)) {}
  Recording(const Recording&) = delete;
  Recording& operator=(const Recording&) = delete;
  Recording& operator=(Recording&&) = delete;

  /// Number of cuts.
  std::size_t cut_count() const {
    std::size_t n = 0;
    check(ygg_recording_cut_count(handle_, &n));
    return n;
  }
  /// Cut `index` (generation, publish and record times, bytes added).
  ygg_cut_info cut(std::size_t index) const {
    ygg_cut_info info{};
    check(ygg_recording_cut(handle_, index, &info));
    return info;
  }
  /// The scene as it was at `unix_ns` (the last cut published at or before it).
  Snapshot at_time(std::uint64_t unix_ns) const {
    ygg_snapshot* s = nullptr;
    check(ygg_recording_at_time(handle_, unix_ns, &s));
    return Snapshot(s);
  }
  /// The cut of `generation` (or the last earlier one).
  Snapshot at_generation(std::uint64_t generation) const {
    ygg_snapshot* s = nullptr;
    check(ygg_recording_at_generation(handle_, generation, &s));
    return Snapshot(s);
  }

private:
  ygg_recording* handle_ = nullptr;
};

/// Records a live scene into a recording folder, one cut per `record_next`.
class Recorder {
public:
  /// Attaches to `scene` (waiting up to `wait_for_writer`) and records into `path`.
  Recorder(const std::string& scene, const std::string& path,
           std::chrono::milliseconds wait_for_writer = std::chrono::milliseconds(0)) {
    check(ygg_recorder_open(scene.c_str(), path.c_str(), static_cast<std::uint64_t>(wait_for_writer.count()),
                            &handle_));
  }
  ~Recorder() {
    if (handle_ != nullptr) {
      ygg_recorder_destroy(handle_);
    }
  }
  Recorder(Recorder&& o) noexcept : handle_(std::exchange(o.handle_, nullptr)) {}
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;
  Recorder& operator=(Recorder&&) = delete;

  /// Records the next cut within `timeout`; whether one was recorded.
  bool record_next(std::chrono::nanoseconds timeout) {
    bool recorded = false;
    check(ygg_recorder_record_next(handle_, static_cast<std::uint64_t>(timeout.count()), &recorded));
    return recorded;
  }

private:
  ygg_recorder* handle_ = nullptr;
};

}  // namespace ygg

#endif  // YGGDRASIL_HPP
