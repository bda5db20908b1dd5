/* The physical limit of a mesh job on this machine: every view's regular ray grid cast in
 * tile packets of the native width by plain C threads on the same Embree 4 library (the one
 * the embreex wheel ships), the origins built in float32 as meshladar builds them, nothing
 * weighed or binned, nothing stored but the hit count. Built and run by job.py, which
 * times it against meshladar's own run of the same views on the same number of threads.
 *
 *   limit MESH.bin PLANS.bin WIDTH THREADS REPEATS
 *   MESH.bin: int64 nv, int64 nf, float32 vertices[nv + 1][3] (one padding row, unit size),
 *             uint32 faces[nf][3]
 *   PLANS.bin: int64 nviews, float32 inv_scale; per view: int64 ns, int64 nt,
 *             float32 direction[3], u[3], v[3], lw[3], s[ns], t[nt]: ray (i, j) starts at
 *             ((s_i u + t_j v) + lw) * inv_scale (float32 operations, in that order) and
 *             travels along direction; rows of nt rays, cast in tiles of 4 x 4 (WIDTH 16),
 *             2 x 4 (8) or 2 x 2 (4), a tile cut by the grid's edge masked.
 * Threads take views in turn from a shared counter. Prints: width, threads, the best
 * pass's wall seconds, Mrays/s and hits.
 */
#include <embree4/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "common.h"

typedef struct {
  int64_t ns, nt;
  const float *d, *u, *v, *lw, *s, *t;
} Plan;

typedef struct {
  RTCScene scene;
  const Plan *plans;
  int64_t nviews;
  int width;
  float inv;
  int64_t *next;            /* the shared view counter */
  int64_t hits, rays;
} Work;

#define TILE_CAST(W, TH, TW, RAYHIT, INTERSECT)                                             \
  {                                                                                         \
    RAYHIT rh __attribute__((aligned(64)));                                                 \
    int valid[W] __attribute__((aligned(64)));                                              \
    for (int64_t a0 = 0; a0 < p->ns; a0 += TH)                                              \
      for (int64_t b0 = 0; b0 < p->nt; b0 += TW) {                                          \
        int m = 0;                                                                          \
        for (int64_t a = a0; a < a0 + TH && a < p->ns; a++)                                 \
          for (int64_t b = b0; b < b0 + TW && b < p->nt; b++) {                             \
            for (int k = 0; k < 3; k++) {                                                   \
              float x = ((float)(p->s[a] * p->u[k]) + (float)(p->t[b] * p->v[k])) + p->lw[k]; \
              org[k][m] = x * w->inv;                                                       \
            }                                                                               \
            m++;                                                                            \
          }                                                                                 \
        for (int k = 0; k < W; k++) {                                                       \
          int i = k < m ? k : 0;                                                            \
          valid[k] = k < m ? -1 : 0;                                                        \
          rh.ray.org_x[k] = org[0][i]; rh.ray.org_y[k] = org[1][i];                         \
          rh.ray.org_z[k] = org[2][i];                                                      \
          rh.ray.dir_x[k] = p->d[0]; rh.ray.dir_y[k] = p->d[1]; rh.ray.dir_z[k] = p->d[2];  \
          rh.ray.tnear[k] = 0.0f; rh.ray.tfar[k] = INFINITY; rh.ray.time[k] = 0.0f;         \
          rh.ray.mask[k] = 0xffffffffu; rh.ray.id[k] = 0; rh.ray.flags[k] = 0;              \
          rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;                                       \
          rh.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;                                       \
        }                                                                                   \
        INTERSECT(valid, w->scene, &rh, &args);                                             \
        for (int k = 0; k < m; k++) w->hits += rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID; \
        w->rays += m;                                                                       \
      }                                                                                     \
  }

static void *cast_views(void *arg) {
  Work *w = arg;
  struct RTCIntersectArguments args;
  rtcInitIntersectArguments(&args);
  args.flags = RTC_RAY_QUERY_FLAG_COHERENT;
  float org[3][16];
  for (;;) {
    int64_t view = __atomic_fetch_add(w->next, 1, __ATOMIC_RELAXED);
    if (view >= w->nviews) return NULL;
    const Plan *p = &w->plans[view];
    if (w->width == 16) TILE_CAST(16, 4, 4, struct RTCRayHit16, rtcIntersect16)
    else if (w->width == 8) TILE_CAST(8, 2, 4, struct RTCRayHit8, rtcIntersect8)
    else TILE_CAST(4, 2, 2, struct RTCRayHit4, rtcIntersect4)
  }
}

int main(int argc, char **argv) {
  if (argc != 6) {
    fprintf(stderr, "usage: limit MESH.bin PLANS.bin WIDTH THREADS REPEATS\n");
    return 2;
  }
  size_t msize, psize;
  char *mesh = slurp(argv[1], &msize), *raw = slurp(argv[2], &psize);
  int width = atoi(argv[3]), threads = atoi(argv[4]), repeats = atoi(argv[5]);
  if ((width != 4 && width != 8 && width != 16) || threads < 1 || threads > 64) {
    fprintf(stderr, "WIDTH: 4, 8 or 16; THREADS: 1 to 64\n");
    return 2;
  }
  RTCDevice dev = rtcNewDevice(NULL);
  RTCScene scene = mesh_scene(dev, mesh);

  int64_t nviews = ((int64_t *)raw)[0];
  float inv = *(float *)(raw + 8);
  Plan *plans = malloc(sizeof(Plan) * nviews);
  const char *q = raw + 12;
  for (int64_t i = 0; i < nviews; i++) {
    Plan *p = &plans[i];
    p->ns = ((const int64_t *)q)[0];
    p->nt = ((const int64_t *)q)[1];
    const float *f = (const float *)(q + 16);
    p->d = f; p->u = f + 3; p->v = f + 6; p->lw = f + 9; p->s = f + 12; p->t = f + 12 + p->ns;
    q += 16 + 4 * (12 + p->ns + p->nt);
  }
  if ((size_t)(q - raw) != psize) { fprintf(stderr, "PLANS.bin: bad size\n"); return 2; }

  double best = 1e300;
  int64_t hits = 0, rays = 0;
  Work *work = calloc(threads, sizeof(Work));
  pthread_t *tid = malloc(sizeof(pthread_t) * threads);
  for (int r = 0; r < repeats; r++) {
    int64_t next = 0;
    double t0 = now();
    for (int k = 0; k < threads; k++) {
      work[k] = (Work){scene, plans, nviews, width, inv, &next, 0, 0};
      pthread_create(&tid[k], NULL, cast_views, &work[k]);
    }
    hits = rays = 0;
    for (int k = 0; k < threads; k++) {
      pthread_join(tid[k], NULL);
      hits += work[k].hits;
      rays += work[k].rays;
    }
    double t = now() - t0;
    if (t < best) best = t;
  }
  printf("%d %d %.6f %.3f %lld %lld\n", width, threads, best, rays / best / 1e6,
         (long long)hits, (long long)rays);
  free(work);
  free(tid);
  free(plans);
  rtcReleaseScene(scene);
  rtcReleaseDevice(dev);
  return 0;
}
