/* The header compiles as C11 and the library links from C: a graph, a snapshot, a query,
 * an error message. Built and run by .ci/cpp (gcc -std=c11 -Wall -Wextra -pedantic). */
#include <stdio.h>
#include <string.h>

#include "yggdrasil.h"

#define CHECK(cond)                                                                   \
  do {                                                                                \
    if (!(cond)) {                                                                    \
      fprintf(stderr, "c_smoke.c:%d: %s failed: %s\n", __LINE__, #cond, ygg_last_error()); \
      return 1;                                                                       \
    }                                                                                 \
  } while (0)

int main(void) {
  ygg_graph *g = NULL;
  uint32_t objects = 0;
  CHECK(ygg_graph_create(&g) == YGG_STATUS_OK);
  CHECK(ygg_graph_add_layer(g, "objects", &objects) == YGG_STATUS_OK);
  CHECK(ygg_graph_add_node(g, 7, objects) == YGG_STATUS_OK);
  const float p[3] = {1.0f, 2.0f, 0.5f};
  CHECK(ygg_graph_set_geometry(g, 7, p, 1) == YGG_STATUS_OK);
  CHECK(ygg_graph_add_node(g, 7, objects) == YGG_STATUS_GRAPH_EDIT);
  CHECK(strstr(ygg_last_error(), "node 7 already exists") != NULL);
  ygg_snapshot *s = NULL;
  CHECK(ygg_graph_snapshot(g, &s) == YGG_STATUS_OK);
  ygg_node_list list = {NULL, NULL, 0};
  const float origin[3] = {0.0f, 0.0f, 0.0f};
  CHECK(ygg_snapshot_nearest_nodes(s, YGG_ALL_LAYERS, origin, 1, &list) == YGG_STATUS_OK);
  CHECK(list.len == 1 && list.ids[0] == 7);
  CHECK(ygg_node_list_free(&list) == YGG_STATUS_OK);
  CHECK(ygg_snapshot_destroy(s) == YGG_STATUS_OK);
  CHECK(ygg_graph_destroy(g) == YGG_STATUS_OK);
  puts("c_smoke: 1 passed, 0 failed");
  return 0;
}
