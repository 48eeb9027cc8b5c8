// Exercises every entry point of the C API (yggdrasil.h), success and error paths, and
// the C++ wrapper (yggdrasil.hpp). Prints one line per failed check and ends with
// "N passed, N failed"; exits 1 if any check failed. Runs under valgrind memcheck in CI.
//
// Usage: capi_test FIXTURES_DIR SCENE
//   FIXTURES_DIR  dsg/tests/fixtures (office_tiny.json for the Spark-DSG import)
//   SCENE         a scene name unique to this run (the writer/reader checks use it)
#include <yggdrasil.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

namespace {
int passed = 0;
int failed = 0;

void expect(bool ok, const char* what, int line) {
  if (ok) {
    ++passed;
  } else {
    ++failed;
    std::fprintf(stderr, "capi_test.cpp:%d: check failed: %s (last error: %s)\n", line, what, ygg_last_error());
  }
}
#define EXPECT(cond) expect((cond), #cond, __LINE__)
#define EXPECT_OK(call) expect((call) == YGG_STATUS_OK, #call, __LINE__)
#define EXPECT_STATUS(call, status) expect((call) == (status), #call " == " #status, __LINE__)

bool error_has(const char* text) { return std::strstr(ygg_last_error(), text) != nullptr; }

/// ids == want.
bool same(const ygg_node_list& list, std::initializer_list<std::uint64_t> want) {
  if (list.len != want.size()) return false;
  std::size_t i = 0;
  for (auto id : want) {
    if (list.ids[i++] != id) return false;
  }
  return true;
}

// Layers and nodes of the hand-built scene.
std::uint32_t rooms = 0, objects = 0, mesh = 0;

void errors_and_names() {
  EXPECT(std::strcmp(ygg_status_name(YGG_STATUS_OK), "YGG_STATUS_OK") == 0);
  EXPECT(std::strcmp(ygg_status_name(YGG_STATUS_PANIC), "YGG_STATUS_PANIC") == 0);
  EXPECT(std::strcmp(ygg_status_name(YGG_STATUS_NOT_FOUND), "YGG_STATUS_NOT_FOUND") == 0);
  EXPECT_STATUS(ygg_graph_create(nullptr), YGG_STATUS_NULL_ARGUMENT);
  EXPECT(error_has("ygg_graph_create") && error_has("`out` is null"));
  EXPECT_OK(ygg_node_list_free(nullptr));
}

/// Builds rooms 1, 2 with objects 10 (chair, at x=1), 11 (lamp, x=3), 20 (chair, x=12);
/// mesh nodes 110, 111, 120 hold their points.
ygg_graph* build_graph() {
  ygg_graph* g = nullptr;
  EXPECT_OK(ygg_graph_create(&g));
  EXPECT_OK(ygg_graph_add_layer(g, "ROOMS", &rooms));
  EXPECT_OK(ygg_graph_add_layer(g, "OBJECTS", &objects));
  EXPECT_OK(ygg_graph_add_layer(g, "MESH", &mesh));
  std::uint32_t found = 99;
  EXPECT_OK(ygg_graph_layer_id(g, "OBJECTS", &found));
  EXPECT(found == objects);
  EXPECT_OK(ygg_graph_add_layer_edge(g, rooms, objects));
  EXPECT_OK(ygg_graph_add_layer_edge(g, objects, mesh));
  for (std::uint64_t room : {1, 2}) {
    EXPECT_OK(ygg_graph_add_node(g, room, rooms));
    EXPECT_OK(ygg_graph_enable_bounding_box(g, room));
  }
  struct Obj {
    std::uint64_t id, room;
    const char* label;
    float x;
  };
  for (Obj o : {Obj{10, 1, "chair", 1.0f}, Obj{11, 1, "lamp", 3.0f}, Obj{20, 2, "chair", 12.0f}}) {
    EXPECT_OK(ygg_graph_add_node(g, o.id, objects));
    EXPECT_OK(ygg_graph_add_label(g, o.id, o.label));
    EXPECT_OK(ygg_graph_nest(g, o.room, o.id));
    EXPECT_OK(ygg_graph_enable_bounding_box(g, o.id));
    EXPECT_OK(ygg_graph_add_node(g, o.id + 100, mesh));
    // Two points: the first set, the second appended (the queries below see both).
    const float first[3] = {o.x, 0.0f, 0.0f};
    const float second[3] = {o.x, 0.5f, 0.0f};
    EXPECT_OK(ygg_graph_set_geometry(g, o.id + 100, first, 1));
    EXPECT_OK(ygg_graph_append_points(g, o.id + 100, second, 1));
    EXPECT_OK(ygg_graph_nest(g, o.id, o.id + 100));
  }
  EXPECT_OK(ygg_graph_set_feature_str(g, 10, "color", "red"));
  EXPECT_OK(ygg_graph_set_feature_int(g, 10, "legs", 4));
  EXPECT_OK(ygg_graph_set_feature_float(g, 10, "mass", 7.5));
  EXPECT_OK(ygg_graph_set_feature_bool(g, 10, "movable", true));
  EXPECT_OK(ygg_graph_set_feature_int(g, 11, "legs", 1));
  EXPECT_OK(ygg_graph_add_edge(g, 10, 11, "next to"));
  EXPECT_OK(ygg_graph_enable_layer_index(g, mesh));
  EXPECT_OK(ygg_graph_enable_node_index(g, 1));
  return g;
}

void graph_mutations_and_their_errors(ygg_graph* g) {
  std::size_t n = 0;
  EXPECT_OK(ygg_graph_node_count(g, &n));
  EXPECT(n == 8);
  std::uint32_t layer = 0;
  EXPECT_STATUS(ygg_graph_add_layer(g, "ROOMS", &layer), YGG_STATUS_GRAPH_EDIT);
  EXPECT(error_has("already exists"));
  EXPECT_STATUS(ygg_graph_add_layer(g, nullptr, &layer), YGG_STATUS_NULL_ARGUMENT);
  EXPECT(error_has("`name` is null"));
  EXPECT_STATUS(ygg_graph_add_layer(g, "bad \xff utf8", &layer), YGG_STATUS_INVALID_ARGUMENT);
  EXPECT(error_has("not UTF-8"));
  EXPECT_STATUS(ygg_graph_add_layer(g, "x", nullptr), YGG_STATUS_NULL_ARGUMENT);
  EXPECT_STATUS(ygg_graph_layer_id(g, "NOPE", &layer), YGG_STATUS_GRAPH_EDIT);
  EXPECT_STATUS(ygg_graph_add_layer_edge(g, mesh, rooms), YGG_STATUS_GRAPH_EDIT);
  EXPECT(error_has("cycle"));
  EXPECT_STATUS(ygg_graph_add_node(g, 10, objects), YGG_STATUS_GRAPH_EDIT);
  EXPECT(error_has("already exists"));
  EXPECT_STATUS(ygg_graph_add_node(g, 77, 4242), YGG_STATUS_GRAPH_EDIT);
  EXPECT(error_has("unknown layer"));
  EXPECT_STATUS(ygg_graph_set_geometry(g, 110, nullptr, 3), YGG_STATUS_NULL_ARGUMENT);
  const float nan_point[3] = {NAN, 0.0f, 0.0f};
  EXPECT(ygg_graph_set_geometry(g, 110, nan_point, 1) != YGG_STATUS_OK);
  EXPECT_STATUS(ygg_graph_append_points(g, 110, nullptr, 2), YGG_STATUS_NULL_ARGUMENT);
  EXPECT_STATUS(ygg_graph_append_points(g, 110, nan_point, 1), YGG_STATUS_GRAPH_EDIT);
  EXPECT(error_has("non-finite"));
  EXPECT_STATUS(ygg_graph_set_feature_float(g, 10, "mass", NAN), YGG_STATUS_GRAPH_EDIT);
  EXPECT_STATUS(ygg_graph_set_feature_int(g, 999, "legs", 1), YGG_STATUS_GRAPH_EDIT);
  EXPECT(error_has("unknown node 999"));
  EXPECT_STATUS(ygg_graph_add_edge(g, 10, 1, "across"), YGG_STATUS_GRAPH_EDIT);  // across layers
  EXPECT_STATUS(ygg_graph_nest(g, 110, 1), YGG_STATUS_GRAPH_EDIT);               // no DAG edge mesh -> rooms
  EXPECT_STATUS(ygg_graph_nest(g, 2, 10), YGG_STATUS_GRAPH_EDIT);                // 10 already has a parent
  EXPECT_STATUS(ygg_graph_remove_layer(g, 4242), YGG_STATUS_GRAPH_EDIT);
  EXPECT_STATUS(ygg_graph_remove_layer_edge(g, rooms, objects), YGG_STATUS_GRAPH_EDIT);  // in use
  EXPECT_STATUS(ygg_graph_remove_node(g, 4242), YGG_STATUS_GRAPH_EDIT);
  EXPECT_STATUS(ygg_graph_enable_layer_index(g, 4242), YGG_STATUS_GRAPH_EDIT);
  EXPECT_STATUS(ygg_graph_enable_node_index(g, 4242), YGG_STATUS_GRAPH_EDIT);
  EXPECT_OK(ygg_graph_node_count(g, &n));
  EXPECT(n == 8);  // every refused mutation left the graph unchanged

  // Mutations that undo themselves: a temporary layer, node, edge, label, feature.
  std::uint32_t tmp = 0;
  EXPECT_OK(ygg_graph_add_layer(g, "TMP", &tmp));
  EXPECT_OK(ygg_graph_add_layer_edge(g, rooms, tmp));
  EXPECT_OK(ygg_graph_add_node(g, 500, tmp));
  EXPECT_OK(ygg_graph_add_node(g, 501, tmp));
  EXPECT_OK(ygg_graph_nest(g, 2, 500));
  EXPECT_OK(ygg_graph_unnest(g, 500));
  EXPECT_OK(ygg_graph_add_edge(g, 500, 501, ""));
  EXPECT_OK(ygg_graph_remove_edge(g, 500, 501));
  EXPECT_STATUS(ygg_graph_remove_edge(g, 500, 501), YGG_STATUS_GRAPH_EDIT);
  EXPECT_OK(ygg_graph_add_label(g, 500, "temp"));
  EXPECT_OK(ygg_graph_remove_label(g, 500, "temp"));
  EXPECT_OK(ygg_graph_set_feature_int(g, 500, "k", 1));
  EXPECT_OK(ygg_graph_remove_feature(g, 500, "k"));
  EXPECT_STATUS(ygg_graph_remove_feature(g, 500, "k"), YGG_STATUS_GRAPH_EDIT);
  EXPECT_OK(ygg_graph_set_geometry(g, 500, nullptr, 0));
  EXPECT_OK(ygg_graph_enable_bounding_box(g, 500));
  EXPECT_OK(ygg_graph_disable_bounding_box(g, 500));
  EXPECT_OK(ygg_graph_enable_node_index(g, 500));
  EXPECT_OK(ygg_graph_disable_node_index(g, 500));
  EXPECT_OK(ygg_graph_enable_layer_index(g, tmp));
  EXPECT_OK(ygg_graph_disable_layer_index(g, tmp));
  EXPECT_OK(ygg_graph_remove_node(g, 500));
  EXPECT_OK(ygg_graph_remove_node(g, 501));
  EXPECT_OK(ygg_graph_remove_layer_edge(g, rooms, tmp));
  EXPECT_OK(ygg_graph_remove_layer(g, tmp));
  EXPECT_OK(ygg_graph_node_count(g, &n));
  EXPECT(n == 8);
}

/// The accessors and queries on a snapshot of build_graph()'s scene.
void snapshot_accessors_and_queries(const ygg_snapshot* s) {
  std::size_t n = 0;
  EXPECT_OK(ygg_snapshot_node_count(s, &n));
  EXPECT(n == 8);
  std::uint64_t generation = 99;
  EXPECT_OK(ygg_snapshot_generation(s, &generation));
  std::uint32_t layer = 0;
  EXPECT_OK(ygg_snapshot_layer_by_name(s, "MESH", &layer));
  EXPECT(layer == mesh);
  EXPECT_STATUS(ygg_snapshot_layer_by_name(s, "NOPE", &layer), YGG_STATUS_NOT_FOUND);
  ygg_node_list list{nullptr, nullptr, 0};
  EXPECT_OK(ygg_snapshot_layer_nodes(s, objects, &list));
  EXPECT(same(list, {10, 11, 20}));
  EXPECT_OK(ygg_node_list_free(&list));
  EXPECT_OK(ygg_node_list_free(&list));  // freeing twice is harmless
  EXPECT_STATUS(ygg_snapshot_layer_nodes(s, 4242, &list), YGG_STATUS_NOT_FOUND);
  EXPECT(list.len == 0 && list.ids == nullptr);

  EXPECT_OK(ygg_snapshot_node_layer(s, 110, &layer));
  EXPECT(layer == mesh);
  EXPECT_STATUS(ygg_snapshot_node_layer(s, 999, &layer), YGG_STATUS_NOT_FOUND);
  EXPECT(error_has("no node 999"));
  const float* xyz = nullptr;
  EXPECT_OK(ygg_snapshot_node_points(s, 110, &xyz, &n));
  EXPECT(n == 2 && xyz != nullptr && xyz[0] == 1.0f && xyz[4] == 0.5f);
  EXPECT_OK(ygg_snapshot_node_points(s, 1, &xyz, &n));
  EXPECT(n == 0 && xyz == nullptr);
  EXPECT_STATUS(ygg_snapshot_node_points(s, 110, nullptr, &n), YGG_STATUS_NULL_ARGUMENT);
  bool has = false;
  std::uint64_t parent = 0;
  EXPECT_OK(ygg_snapshot_node_parent(s, 110, &has, &parent));
  EXPECT(has && parent == 10);
  EXPECT_OK(ygg_snapshot_node_parent(s, 1, &has, &parent));
  EXPECT(!has);
  ygg_node_list children{nullptr, nullptr, 0};
  EXPECT_OK(ygg_snapshot_node_children(s, 1, &children));
  EXPECT(children.len == 2 && children.ids[0] == 10 && children.ids[1] == 11);
  ygg_node_list_free(&children);
  EXPECT_STATUS(ygg_snapshot_node_children(s, 999, &children), YGG_STATUS_NOT_FOUND);
  EXPECT(children.len == 0);
  EXPECT_STATUS(ygg_snapshot_node_children(s, 1, nullptr), YGG_STATUS_NULL_ARGUMENT);
  float box[6] = {};
  EXPECT_OK(ygg_snapshot_node_aabb(s, 1, &has, box));
  EXPECT(has && box[0] == 1.0f && box[3] == 3.0f && box[4] == 0.5f);
  EXPECT_OK(ygg_snapshot_node_aabb(s, 110, &has, box));
  EXPECT(!has);
  EXPECT_OK(ygg_snapshot_node_has_label(s, 10, "chair", &has));
  EXPECT(has);
  EXPECT_OK(ygg_snapshot_node_has_label(s, 10, "lamp", &has));
  EXPECT(!has);
  EXPECT_OK(ygg_snapshot_node_label_count(s, 10, &n));
  EXPECT(n == 1);
  const char* label = nullptr;
  EXPECT_OK(ygg_snapshot_node_label(s, 10, 0, &label, &n));
  EXPECT(std::string(label, n) == "chair");
  EXPECT_STATUS(ygg_snapshot_node_label(s, 10, 1, &label, &n), YGG_STATUS_NOT_FOUND);
  ygg_feature f{};
  EXPECT_OK(ygg_snapshot_node_feature(s, 10, "color", &f));
  EXPECT(f.kind == YGG_FEATURE_KIND_STR && std::string(f.str, f.str_len) == "red");
  EXPECT_OK(ygg_snapshot_node_feature(s, 10, "legs", &f));
  EXPECT(f.kind == YGG_FEATURE_KIND_INT && f.int_value == 4);
  EXPECT_OK(ygg_snapshot_node_feature(s, 10, "mass", &f));
  EXPECT(f.kind == YGG_FEATURE_KIND_FLOAT && f.float_value == 7.5);
  EXPECT_OK(ygg_snapshot_node_feature(s, 10, "movable", &f));
  EXPECT(f.kind == YGG_FEATURE_KIND_BOOL && f.bool_value);
  EXPECT_STATUS(ygg_snapshot_node_feature(s, 10, "absent", &f), YGG_STATUS_NOT_FOUND);

  // The store's queries.
  const float origin[3] = {0.0f, 0.0f, 0.0f};
  EXPECT_OK(ygg_snapshot_nearest_nodes(s, mesh, origin, 2, &list));
  EXPECT(same(list, {110, 111}) && list.distances != nullptr && list.distances[0] == 1.0f);
  ygg_node_list_free(&list);
  EXPECT_OK(ygg_snapshot_nearest_nodes(s, YGG_ALL_LAYERS, origin, 1, &list));
  EXPECT(same(list, {110}));
  ygg_node_list_free(&list);
  EXPECT_STATUS(ygg_snapshot_nearest_nodes(s, mesh, nullptr, 1, &list), YGG_STATUS_NULL_ARGUMENT);
  const float bad[3] = {NAN, 0.0f, 0.0f};
  EXPECT_STATUS(ygg_snapshot_nearest_nodes(s, mesh, bad, 1, &list), YGG_STATUS_INVALID_ARGUMENT);
  EXPECT(error_has("query refused") && list.len == 0);
  EXPECT_OK(ygg_snapshot_nodes_within_radius(s, YGG_ALL_LAYERS, origin, 3.0f, &list));
  EXPECT(same(list, {110, 111}));
  ygg_node_list_free(&list);
  EXPECT_STATUS(ygg_snapshot_nodes_within_radius(s, mesh, origin, -1.0f, &list), YGG_STATUS_INVALID_ARGUMENT);
  const float far[3] = {12.0f, 0.0f, 0.0f};
  EXPECT_OK(ygg_snapshot_nearest_in_subtree(s, 1, far, 1, &list));  // room 1 only: 111 at x=3
  EXPECT(same(list, {111}) && list.distances[0] == 9.0f);
  ygg_node_list_free(&list);
  const float dir[3] = {1.0f, 0.0f, 0.0f};
  EXPECT_OK(ygg_snapshot_visible(s, 1, origin, dir, 17.0f, 2.0f, &list));  // degrees, as everywhere
  EXPECT(same(list, {110}));
  ygg_node_list_free(&list);
  EXPECT_STATUS(ygg_snapshot_visible(s, 1, origin, dir, 200.0f, 2.0f, &list), YGG_STATUS_INVALID_ARGUMENT);
  EXPECT_OK(ygg_snapshot_nodes_with_label(s, YGG_ALL_LAYERS, "chair", &list));
  EXPECT(same(list, {10, 20}));
  ygg_node_list_free(&list);
  EXPECT_OK(ygg_snapshot_nodes_with_label(s, rooms, "chair", &list));
  EXPECT(list.len == 0);
  const char* keys[] = {"legs"};
  EXPECT_OK(ygg_snapshot_nodes_having(s, YGG_ALL_LAYERS, keys, 1, &list));
  EXPECT(same(list, {10, 11}));
  ygg_node_list_free(&list);
  EXPECT_STATUS(ygg_snapshot_nodes_having(s, YGG_ALL_LAYERS, nullptr, 1, &list), YGG_STATUS_NULL_ARGUMENT);
  EXPECT_OK(ygg_snapshot_subtree(s, 1, &list));
  EXPECT(same(list, {1, 10, 11, 110, 111}));
  ygg_node_list_free(&list);

  // The object contract (Q1a, Q1b, Q2, Q3).
  bool found = false;
  std::uint64_t object = 0;
  const float near_lamp[3] = {3.2f, 0.0f, 0.0f};
  EXPECT_OK(ygg_snapshot_nearest_object(s, near_lamp, &found, &object));
  EXPECT(found && object == 11);
  EXPECT_STATUS(ygg_snapshot_nearest_object(s, bad, &found, &object), YGG_STATUS_INVALID_ARGUMENT);
  EXPECT_OK(ygg_snapshot_objects_within(s, origin, 3.0f, &list));
  EXPECT(same(list, {10, 11}));
  ygg_node_list_free(&list);
  EXPECT_OK(ygg_snapshot_visible_objects(s, origin, dir, 30.0f, 20.0f, &list));
  EXPECT(same(list, {10, 11, 20}));
  ygg_node_list_free(&list);
  EXPECT_STATUS(ygg_snapshot_visible_objects(s, origin, dir, 200.0f, 20.0f, &list), YGG_STATUS_INVALID_ARGUMENT);
  EXPECT(error_has("half_angle_deg"));
  EXPECT_OK(ygg_snapshot_objects_with_label(s, "chair", &list));
  EXPECT(same(list, {10, 20}));
  ygg_node_list_free(&list);
  EXPECT_OK(ygg_snapshot_objects_with_label(s, "unicorn", &list));
  EXPECT(list.len == 0);
}

/// A snapshot is shared by threads: each runs the queries at once (documented as safe).
void snapshot_shared_by_threads(const ygg_snapshot* s) {
  std::vector<int> wrong(4, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([s, t, &wrong] {
      const float near_lamp[3] = {3.2f, 0.0f, 0.0f};
      for (int i = 0; i < 200; ++i) {
        bool found = false;
        std::uint64_t object = 0;
        ygg_node_list list{nullptr, nullptr, 0};
        if (ygg_snapshot_nearest_object(s, near_lamp, &found, &object) != YGG_STATUS_OK || object != 11) ++wrong[t];
        if (ygg_snapshot_objects_with_label(s, "chair", &list) != YGG_STATUS_OK || !same(list, {10, 20})) ++wrong[t];
        ygg_node_list_free(&list);
      }
    });
  }
  for (auto& th : threads) th.join();
  for (int w : wrong) EXPECT(w == 0);
}

void handle_misuse(ygg_graph* g, ygg_snapshot* s) {
  // Null, destroyed and wrongly typed handles are errors, never dereferenced.
  EXPECT_STATUS(ygg_graph_add_node(nullptr, 1, 0), YGG_STATUS_NULL_ARGUMENT);
  EXPECT(error_has("`graph` is null"));
  EXPECT_STATUS(ygg_graph_add_node(reinterpret_cast<ygg_graph*>(s), 1, 0), YGG_STATUS_INVALID_HANDLE);
  EXPECT(error_has("is a Snapshot handle, not a graph handle"));
  std::size_t n = 0;
  EXPECT_STATUS(ygg_snapshot_node_count(reinterpret_cast<ygg_snapshot*>(g), &n), YGG_STATUS_INVALID_HANDLE);
  int not_a_handle = 0;
  EXPECT_STATUS(ygg_writer_publish(reinterpret_cast<ygg_writer*>(&not_a_handle), nullptr), YGG_STATUS_INVALID_HANDLE);
  EXPECT(error_has("not a live writer handle"));
  ygg_graph* dead = nullptr;
  EXPECT_OK(ygg_graph_create(&dead));
  EXPECT_OK(ygg_graph_node_count(dead, &n));  // this thread's last live handle: the cached check
  EXPECT_OK(ygg_graph_destroy(dead));
  EXPECT_STATUS(ygg_graph_add_node(dead, 1, 0), YGG_STATUS_INVALID_HANDLE);
  EXPECT_STATUS(ygg_graph_destroy(dead), YGG_STATUS_INVALID_HANDLE);  // double destroy
  EXPECT_STATUS(ygg_snapshot_destroy(nullptr), YGG_STATUS_NULL_ARGUMENT);
  EXPECT_STATUS(ygg_reader_destroy(nullptr), YGG_STATUS_NULL_ARGUMENT);
  EXPECT_STATUS(ygg_writer_destroy(nullptr), YGG_STATUS_NULL_ARGUMENT);
}

void files_and_import(ygg_graph* g, const std::string& fixtures, const std::string& dir) {
  const std::string path = dir + "/scene.ygg";
  EXPECT_OK(ygg_graph_save(g, path.c_str()));
  EXPECT_STATUS(ygg_graph_save(g, "/nonexistent-dir/x.ygg"), YGG_STATUS_IO);
  EXPECT(error_has("/nonexistent-dir/x.ygg"));
  ygg_snapshot* file = nullptr;
  EXPECT_OK(ygg_snapshot_open_file(path.c_str(), &file));
  if (file != nullptr) snapshot_accessors_and_queries(file);
  EXPECT_OK(ygg_snapshot_destroy(file));
  ygg_snapshot* none = nullptr;
  EXPECT_STATUS(ygg_snapshot_open_file("/nonexistent.ygg", &none), YGG_STATUS_IO);
  const std::string garbage = dir + "/garbage.ygg";
  if (FILE* out = std::fopen(garbage.c_str(), "w")) {
    std::fputs("not a snapshot", out);
    std::fclose(out);
  }
  EXPECT_STATUS(ygg_snapshot_open_file(garbage.c_str(), &none), YGG_STATUS_IO);
  EXPECT(none == nullptr);

  ygg_graph* office = nullptr;
  const std::string tiny = fixtures + "/office_tiny.json";
  EXPECT_OK(ygg_graph_import_dsg(tiny.c_str(), "mint", false, &office));
  std::size_t n = 0;
  EXPECT_OK(ygg_graph_node_count(office, &n));
  EXPECT(n > 110);  // 110 Spark-DSG nodes plus the layout's group and mesh nodes
  ygg_snapshot* s = nullptr;
  EXPECT_OK(ygg_graph_snapshot(office, &s));
  ygg_node_list list{nullptr, nullptr, 0};
  const float p[3] = {5.0f, 5.0f, 1.0f};
  EXPECT_OK(ygg_snapshot_objects_within(s, p, 100.0f, &list));
  EXPECT(list.len == 34);  // every object of office_tiny
  ygg_node_list_free(&list);
  EXPECT_OK(ygg_snapshot_destroy(s));
  EXPECT_OK(ygg_graph_destroy(office));
  const std::string binary = fixtures + "/office_tiny.sparkdsg";
  EXPECT_OK(ygg_graph_import_dsg(binary.c_str(), "vanilla", true, &office));
  EXPECT_OK(ygg_graph_destroy(office));
  EXPECT_STATUS(ygg_graph_import_dsg(tiny.c_str(), "caramel", false, &office), YGG_STATUS_INVALID_ARGUMENT);
  EXPECT(error_has("unknown layout"));
  EXPECT_STATUS(ygg_graph_import_dsg("/nonexistent.json", "mint", false, &office), YGG_STATUS_IMPORT);
  EXPECT_STATUS(ygg_graph_import_dsg(garbage.c_str(), "mint", false, &office), YGG_STATUS_IMPORT);
}

void writer_and_reader(const std::string& scene) {
  ygg_reader* reader = nullptr;
  ygg_reader_options no_wait{0, false, false};
  EXPECT_STATUS(ygg_reader_open(scene.c_str(), &no_wait, &reader), YGG_STATUS_READER_OPEN);
  EXPECT(error_has("no writer"));

  ygg_graph* g = build_graph();
  ygg_writer* writer = nullptr;
  EXPECT_STATUS(ygg_writer_create("bad scene name!", g, nullptr, &writer), YGG_STATUS_WRITER_CREATE);
  std::size_t n = 0;
  EXPECT_OK(ygg_graph_node_count(g, &n));  // a failed create leaves the graph with the caller
  EXPECT(n == 8);
  ygg_writer_options options{4, 4096, 0, 0};
  EXPECT_OK(ygg_writer_create(scene.c_str(), g, &options, &writer));
  EXPECT_STATUS(ygg_graph_node_count(g, &n), YGG_STATUS_INVALID_HANDLE);  // moved into the writer
  ygg_graph* other = build_graph();
  ygg_writer* second = nullptr;
  EXPECT_STATUS(ygg_writer_create(scene.c_str(), other, nullptr, &second), YGG_STATUS_WRITER_CREATE);
  EXPECT_OK(ygg_graph_destroy(other));
  ygg_graph* live = nullptr;
  ygg_graph* again = nullptr;
  EXPECT_OK(ygg_writer_graph(writer, &live));
  EXPECT_OK(ygg_writer_graph(writer, &again));
  EXPECT(live == again);
  EXPECT_STATUS(ygg_graph_destroy(live), YGG_STATUS_INVALID_ARGUMENT);
  EXPECT(error_has("belongs to a writer"));
  EXPECT_STATUS(ygg_writer_create("another", live, nullptr, &second), YGG_STATUS_INVALID_ARGUMENT);
  ygg_publish_report report{};
  EXPECT_OK(ygg_writer_publish(writer, &report));
  EXPECT(report.generation == 1 && report.layers_sent == 3 && report.bytes_sent > 0);
  ygg_writer_status_info status{};
  EXPECT_OK(ygg_writer_status(writer, &status));
  EXPECT(status.generation == 1 && status.node_count == 8 && status.layer_count == 3);
  bool stop = true;
  EXPECT_OK(ygg_writer_wait(writer, 1000000, &stop));
  EXPECT(!stop);

  // A graph past the writer's layer bound is refused at publish, naming the bound.
  ygg_graph* three_layers = build_graph();
  ygg_writer_options bounded{0, 0, 2, 0};
  ygg_writer* bounded_writer = nullptr;
  EXPECT_OK(ygg_writer_create((scene + "-bound").c_str(), three_layers, &bounded, &bounded_writer));
  EXPECT_STATUS(ygg_writer_publish(bounded_writer, &report), YGG_STATUS_PUBLISH);
  EXPECT(error_has("max_layers"));
  EXPECT_OK(ygg_writer_destroy(bounded_writer));

  ygg_reader_options wait{5000, false, false};
  EXPECT_OK(ygg_reader_open(scene.c_str(), &wait, &reader));
  ygg_snapshot* s = nullptr;
  EXPECT_OK(ygg_reader_wait_next(reader, 5000000000ull, &s));
  EXPECT(s != nullptr);
  if (s != nullptr) {
    snapshot_accessors_and_queries(s);
    std::uint64_t generation = 0;
    EXPECT_OK(ygg_snapshot_generation(s, &generation));
    EXPECT(generation == 1);
  }
  // A mutation through the writer's graph reaches the reader at the next publish.
  const float moved[3] = {2.0f, 0.0f, 0.0f};
  EXPECT_OK(ygg_graph_set_geometry(live, 110, moved, 1));
  EXPECT_OK(ygg_writer_publish(writer, &report));
  EXPECT(report.generation == 2 && report.layers_sent + report.layers_unchanged == 3);
  ygg_snapshot* next = nullptr;
  EXPECT_OK(ygg_reader_wait_next(reader, 5000000000ull, &next));
  if (next != nullptr) {
    const float* xyz = nullptr;
    EXPECT_OK(ygg_snapshot_node_points(next, 110, &xyz, &n));
    EXPECT(n == 1 && xyz[0] == 2.0f);
    const float* old = nullptr;
    EXPECT_OK(ygg_snapshot_node_points(s, 110, &old, &n));  // the old snapshot is unchanged
    EXPECT(n == 2 && old[0] == 1.0f);
  }
  ygg_snapshot* latest = nullptr;
  EXPECT_OK(ygg_reader_latest(reader, &latest));
  EXPECT(latest != nullptr);
  ygg_snapshot* timeout = reinterpret_cast<ygg_snapshot*>(&n);
  EXPECT_OK(ygg_reader_wait_next(reader, 1000000, &timeout));
  EXPECT(timeout == nullptr);
  EXPECT_STATUS(ygg_reader_wait_next(reader, 1000000, nullptr), YGG_STATUS_NULL_ARGUMENT);
  ygg_writer_state state = YGG_WRITER_STATE_GONE;
  EXPECT_OK(ygg_reader_writer_status(reader, &state));
  EXPECT(state != YGG_WRITER_STATE_GONE);
  bool requested = true;
  EXPECT_OK(ygg_reader_termination_requested(reader, &requested));
  EXPECT(!requested);

  EXPECT_OK(ygg_writer_destroy(writer));
  EXPECT_STATUS(ygg_graph_node_count(live, &n), YGG_STATUS_INVALID_HANDLE);  // went with its writer
  EXPECT_STATUS(ygg_writer_publish(writer, nullptr), YGG_STATUS_INVALID_HANDLE);
  // The reader keeps its snapshots and reports the writer gone.
  for (int i = 0; i < 50 && state != YGG_WRITER_STATE_GONE; ++i) {
    ygg_snapshot* none = nullptr;
    ygg_reader_wait_next(reader, 100000000, &none);
    if (none != nullptr) ygg_snapshot_destroy(none);
    EXPECT_OK(ygg_reader_writer_status(reader, &state));
  }
  EXPECT(state == YGG_WRITER_STATE_GONE);
  if (latest != nullptr) {
    EXPECT_OK(ygg_snapshot_node_count(latest, &n));
    EXPECT(n == 8);
  }
  EXPECT_OK(ygg_reader_destroy(reader));
  for (ygg_snapshot* held : {s, next, latest}) {
    if (held != nullptr) EXPECT_OK(ygg_snapshot_destroy(held));
  }
}

// A layer split into parts of 4 rows (`part_rows`), growing by appends, edited in the middle
// and trimmed at the front: a C reader's answers equal those of the live graph's snapshot,
// and an append resends a few parts, not the layer.
void parts_of_a_growing_layer(const std::string& scene) {
  ygg_graph* g = nullptr;
  EXPECT_OK(ygg_graph_create(&g));
  std::uint32_t poses = 0;
  EXPECT_OK(ygg_graph_add_layer(g, "POSES", &poses));
  EXPECT_OK(ygg_graph_enable_layer_index(g, poses));
  ygg_writer_options options{};
  options.part_rows = 4;
  ygg_writer* writer = nullptr;
  EXPECT_OK(ygg_writer_create((scene + "-parts").c_str(), g, &options, &writer));
  ygg_graph* live = nullptr;
  EXPECT_OK(ygg_writer_graph(writer, &live));
  ygg_reader* reader = nullptr;
  ygg_reader_options wait{5000, false, false};
  ygg_publish_report report{};
  std::uint64_t next = 100;
  const auto append = [&](int count) {
    for (int k = 0; k < count; ++k, ++next) {
      const float xyz[3] = {0.5f * static_cast<float>(next), 1.0f, 0.0f};
      EXPECT_OK(ygg_graph_add_node(live, next, poses));
      EXPECT_OK(ygg_graph_set_geometry(live, next, xyz, 1));
      if (next > 100) EXPECT_OK(ygg_graph_add_edge(live, next - 1, next, "odometry"));
    }
  };
  const auto nearest = [&](const ygg_snapshot* s, const float* c) {
    ygg_node_list list{nullptr, nullptr, 0};
    EXPECT_OK(ygg_snapshot_nearest_nodes(s, poses, c, 3, &list));
    std::vector<std::uint64_t> ids(list.ids, list.ids + list.len);
    EXPECT_OK(ygg_node_list_free(&list));
    return ids;
  };
  for (int step = 0; step < 12; ++step) {
    append(10);
    if (step == 6) {
      const float moved[3] = {3.0f, 9.0f, 0.0f};
      EXPECT_OK(ygg_graph_set_geometry(live, 110, moved, 1));  // an edit in an old part
      for (std::uint64_t old = 100; old < 105; ++old) EXPECT_OK(ygg_graph_remove_node(live, old));
    }
    EXPECT_OK(ygg_writer_publish(writer, &report));
    if (reader == nullptr) EXPECT_OK(ygg_reader_open((scene + "-parts").c_str(), &wait, &reader));
    ygg_snapshot* got = nullptr;
    EXPECT_OK(ygg_reader_wait_next(reader, 5000000000ull, &got));
    ygg_snapshot* truth = nullptr;
    EXPECT_OK(ygg_graph_snapshot(live, &truth));
    if (got != nullptr && truth != nullptr) {
      std::size_t a = 0, b = 0;
      EXPECT_OK(ygg_snapshot_node_count(got, &a));
      EXPECT_OK(ygg_snapshot_node_count(truth, &b));
      EXPECT(a == b);
      for (float x : {0.0f, 7.3f, 30.0f, 80.0f}) {
        const float c[3] = {x, 1.0f, 0.0f};
        EXPECT(nearest(got, c) == nearest(truth, c));
      }
    }
    for (ygg_snapshot* held : {got, truth}) {
      if (held != nullptr) EXPECT_OK(ygg_snapshot_destroy(held));
    }
  }
  EXPECT(report.segments > 10);  // the poses lie in many parts
  append(1);
  EXPECT_OK(ygg_writer_publish(writer, &report));
  // The new node's part and its predecessor's (the odometry edge), perhaps a merge of cold
  // parts: a few parts, not the layer.
  EXPECT(report.layers_sent == 1 && report.parts_sent >= 1 && 2 * report.parts_sent < report.segments);
  if (reader != nullptr) EXPECT_OK(ygg_reader_destroy(reader));
  EXPECT_OK(ygg_writer_destroy(writer));
}

void cpp_wrapper(const std::string& scene) {
  ygg::SceneGraph g;
  const auto rooms = g.add_layer("ROOMS");
  const auto objects = g.add_layer("OBJECTS");
  g.add_layer_edge(rooms, objects);
  g.add_node(1, rooms);
  g.enable_bounding_box(1);
  g.add_node(7, objects);
  g.set_geometry(7, std::vector<ygg::Point>{{1.0f, 2.0f, 0.5f}, {1.5f, 2.0f, 0.5f}});
  g.add_label(7, "chair");
  g.set_feature(7, "legs", 4);
  g.nest(1, 7);
  try {
    g.add_node(7, objects);
    EXPECT(false);
  } catch (const ygg::Error& e) {
    EXPECT(e.status() == YGG_STATUS_GRAPH_EDIT && std::strstr(e.what(), "node 7 already exists") != nullptr);
  }
  {
    ygg::Snapshot local = g.snapshot();
    EXPECT(local.nodes_with_label("chair") == std::vector<ygg::NodeId>{7});
    EXPECT(local.parent(7) == std::optional<ygg::NodeId>(1));
    EXPECT(!local.layer_by_name("NOPE"));
    EXPECT(local.labels(7).size() == 1 && local.labels(7)[0] == "chair");
    EXPECT(local.feature(7, "legs")->int_value == 4 && !local.feature(7, "nope"));
    EXPECT(local.aabb(1).has_value() && (*local.aabb(1))[3] == 1.5f);
  }
  ygg::Writer writer(scene + "-cpp", std::move(g));
  EXPECT(g.handle() == nullptr);
  writer.graph().set_point(7, {3.0f, 2.0f, 0.5f});
  EXPECT(writer.publish().generation == 1);
  EXPECT(writer.status().node_count == 2);
  EXPECT(writer.wait(std::chrono::milliseconds(1)));
  ygg::Reader reader(scene + "-cpp", std::chrono::seconds(5));
  std::optional<ygg::Snapshot> snapshot = reader.wait_next(std::chrono::seconds(5));
  EXPECT(snapshot.has_value());
  if (snapshot) {
    const ygg::Points points = snapshot->points(7);
    EXPECT(points.size() == 1 && points[0][0] == 3.0f && points.data() != nullptr);
    std::size_t count = 0;
    for (ygg::Point p : points) count += p[1] == 2.0f;
    EXPECT(count == 1 && points.end() - points.begin() == 1);
    EXPECT(snapshot->nearest_nodes({0.0f, 0.0f, 0.0f}, 1).at(0).id == 7);
    EXPECT(snapshot->children(1) == std::vector<ygg::NodeId>{7});
    EXPECT(snapshot->layer_of(7) == objects);
    try {
      snapshot->points(99);
      EXPECT(false);
    } catch (const ygg::Error& e) {
      EXPECT(e.status() == YGG_STATUS_NOT_FOUND);
    }
  }
  EXPECT(reader.latest().has_value());
  try {
    ygg::Reader missing("no-writer-here-" + scene);
    EXPECT(false);
  } catch (const ygg::Error& e) {
    EXPECT(e.status() == YGG_STATUS_READER_OPEN);
  }
}

// Where the agent is (ygg_dsg::layout through the C API and the C++ wrapper), and the
// transport's log level.
void whereabouts_and_log_level(const std::string& fixtures) {
  ygg::SceneGraph g;
  const auto rooms_l = g.add_layer("ROOMS");
  const auto objects_l = g.add_layer("OBJECTS");
  const auto mesh_l = g.add_layer("MESH");
  const auto agents_l = g.add_layer("AGENTS");
  g.add_layer_edge(rooms_l, objects_l);
  g.add_layer_edge(objects_l, mesh_l);
  for (ygg::NodeId room : {1, 2}) {
    const float x0 = room == 1 ? 0.0f : 10.0f;
    g.add_node(room, rooms_l);
    g.set_geometry(room, std::vector<ygg::Point>{{x0, 0.0f, 0.0f}, {x0 + 5.0f, 4.0f, 3.0f}});
    g.enable_bounding_box(room);
  }
  g.add_node(20, objects_l);
  g.nest(2, 20);
  g.add_node(30, mesh_l);
  g.set_geometry(30, std::vector<ygg::Point>{{12.0f, 2.0f, 0.5f}});
  g.nest(20, 30);
  const float xs[] = {1.0f, 9.0f, 12.0f};
  for (ygg::NodeId pose = 100; pose < 103; ++pose) {
    g.add_node(pose, agents_l);
    g.set_geometry(pose, std::vector<ygg::Point>{{xs[pose - 100], 2.0f, 1.0f}});
  }
  const ygg::Snapshot s = g.snapshot();
  const auto pose = s.newest_pose();
  EXPECT(pose.has_value() && pose->node == 102 && pose->position[0] == 12.0f && pose->previous[0] == 9.0f);
  EXPECT(pose.has_value() && pose->heading[0] == 1.0f && pose->heading[1] == 0.0f);
  EXPECT(s.room_of({12.0f, 2.0f, 1.0f}) == std::optional<ygg::NodeId>(2));
  EXPECT(s.room_of({1.0f, 1.0f, 9.0f}) == std::optional<ygg::NodeId>(1));  // x and y only
  EXPECT(!s.room_of({7.0f, 1.0f, 0.0f}));
  EXPECT(!s.room_scope(2));  // not a per-room layout
  EXPECT((s.owners({30, 30, 20, 999}) == std::vector<ygg::NodeId>{2, 20}));
  EXPECT(!ygg::SceneGraph().snapshot().newest_pose());
  // The C calls' argument checks.
  bool found = true;
  ygg_agent_pose raw{};
  std::uint64_t room = 0;
  const float at[3] = {12.0f, 2.0f, 1.0f};
  EXPECT_STATUS(ygg_snapshot_newest_pose(s.handle(), nullptr, &raw), YGG_STATUS_NULL_ARGUMENT);
  EXPECT_STATUS(ygg_snapshot_room_of(s.handle(), nullptr, &found, &room), YGG_STATUS_NULL_ARGUMENT);
  EXPECT_OK(ygg_snapshot_room_of(s.handle(), at, &found, &room));
  EXPECT(found && room == 2);
  ygg_node_list list{nullptr, nullptr, 0};
  EXPECT_STATUS(ygg_snapshot_owners(s.handle(), nullptr, 2, &list), YGG_STATUS_NULL_ARGUMENT);
  EXPECT(list.len == 0);
  EXPECT_OK(ygg_snapshot_owners(s.handle(), nullptr, 0, &list));
  EXPECT(list.len == 0);
  // A per-room layout: a room's scope names a layer and a node of the snapshot.
  const ygg::Snapshot office = ygg::SceneGraph::import_dsg(fixtures + "/office_tiny.json", "mint").snapshot();
  const auto rooms_of_office = office.layer_nodes(*office.layer_by_name("ROOMS"));
  std::size_t scoped = 0;
  for (ygg::NodeId r : rooms_of_office) {
    const auto scope = office.room_scope(r);
    if (!scope) continue;
    ++scoped;
    ygg_node_list mesh_nodes{nullptr, nullptr, 0};
    EXPECT_OK(ygg_snapshot_layer_nodes(office.handle(), scope->mesh_layer, &mesh_nodes));  // a layer
    ygg_node_list_free(&mesh_nodes);
    EXPECT(!office.subtree(scope->claimed).empty());  // a node (an unknown root's sub-tree is empty)
  }
  EXPECT(scoped > 0);
  // The log level: names, and the error for another.
  ygg::set_log_level("error");
  EXPECT_STATUS(ygg_set_log_level("loud"), YGG_STATUS_INVALID_ARGUMENT);
  EXPECT(error_has("loud"));
  EXPECT_STATUS(ygg_set_log_level(nullptr), YGG_STATUS_NULL_ARGUMENT);
}
// Recording a live scene and going back to any recorded moment (ygg_recorder,
// ygg_recording) through the C++ wrapper, and the C calls' argument checks.
void recording_and_time_travel(const std::string& scene, const std::string& dir) {
  ygg::SceneGraph g;
  const auto objects = g.add_layer("OBJECTS");
  g.add_node(7, objects);
  g.set_point(7, {0.0f, 0.0f, 0.0f});
  ygg::Writer writer(scene + "-rec", std::move(g));
  writer.publish();
  const std::string path = dir + "/run.yggrec";
  std::vector<std::pair<std::uint64_t, float>> expected;  // (generation, x of node 7)
  {
    ygg::Recorder recorder(scene + "-rec", path, std::chrono::seconds(5));
    EXPECT(recorder.record_next(std::chrono::seconds(5)));
    expected.emplace_back(1, 0.0f);
    for (int tick = 1; tick <= 4; ++tick) {
      writer.graph().set_point(7, {float(tick), 0.0f, 0.0f});
      const auto generation = writer.publish().generation;
      EXPECT(recorder.record_next(std::chrono::seconds(5)));
      expected.emplace_back(generation, float(tick));
    }
  }
  const ygg::Recording recording(path);
  EXPECT(recording.cut_count() == expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const ygg_cut_info cut = recording.cut(i);
    EXPECT(cut.generation == expected[i].first);
    EXPECT(recording.at_generation(cut.generation).points(7)[0][0] == expected[i].second);
    EXPECT(recording.at_time(cut.writer_unix_ns).points(7)[0][0] == expected[i].second);
  }
  try {
    recording.at_time(0);
    EXPECT(false);
  } catch (const ygg::Error& e) {
    EXPECT(e.status() == YGG_STATUS_NOT_FOUND);
  }
  try {
    recording.cut(expected.size());
    EXPECT(false);
  } catch (const ygg::Error& e) {
    EXPECT(e.status() == YGG_STATUS_NOT_FOUND);
  }
  try {
    ygg::Recording missing(dir + "/no-such-recording");
    EXPECT(false);
  } catch (const ygg::Error& e) {
    EXPECT(e.status() == YGG_STATUS_IO && std::strstr(e.what(), "no-such-recording") != nullptr);
  }
  EXPECT_STATUS(ygg_recording_open(nullptr, nullptr), YGG_STATUS_NULL_ARGUMENT);
  std::size_t count = 0;
  EXPECT_STATUS(ygg_recording_cut_count(nullptr, &count), YGG_STATUS_NULL_ARGUMENT);
  std::filesystem::remove_all(path);
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: capi_test FIXTURES_DIR SCENE\n");
    return 2;
  }
  const std::string fixtures = argv[1], scene = argv[2];
  char dir_template[] = "/tmp/ygg-capi-test-XXXXXX";
  const char* dir = mkdtemp(dir_template);
  if (dir == nullptr) {
    std::perror("mkdtemp");
    return 2;
  }
  errors_and_names();
  ygg_graph* g = build_graph();
  graph_mutations_and_their_errors(g);
  ygg_snapshot* s = nullptr;
  EXPECT_OK(ygg_graph_snapshot(g, &s));
  snapshot_accessors_and_queries(s);
  snapshot_shared_by_threads(s);
  handle_misuse(g, s);
  files_and_import(g, fixtures, dir);
  EXPECT_OK(ygg_snapshot_destroy(s));
  EXPECT_OK(ygg_graph_destroy(g));
  writer_and_reader(scene);
  parts_of_a_growing_layer(scene);
  cpp_wrapper(scene);
  recording_and_time_travel(scene, dir);
  whereabouts_and_log_level(fixtures);
  const std::string cleanup = std::string(dir) + "/scene.ygg";
  std::remove(cleanup.c_str());
  std::remove((std::string(dir) + "/garbage.ygg").c_str());
  rmdir(dir);
  std::printf("capi_test: %d passed, %d failed\n", passed, failed);
  return failed == 0 ? 0 : 1;
}
