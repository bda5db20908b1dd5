/* A native C reference for meshladar's packet backend: the same Embree 4 library (the one
 * the embreex wheel ships), the same shared-buffer scene, the same rays, cast in coherent
 * packets of width W (1, 4, 8 or 16) by a plain C loop. Built and run by native.py, which
 * times it against meshladar's numba loop on the same rays, interleaved.
 *
 *   packets MESH.bin RAYS.bin WIDTH REPEATS MODE [PRIMS.bin]
 *   MESH.bin: int64 nv, int64 nf, float32 vertices[nv + 1][3] (one padding row),
 *             uint32 faces[nf][3]
 *   RAYS.bin: int64 nviews; per view: int64 n, int64 columns, float32 direction[3],
 *             float32 origins[n][3] (a grid, row-major in rows of columns rays)
 *   MODE rows: packets of W consecutive rays, the last one's tail masked; the hits and the
 *             sum of their primIDs are counted in the loop.
 *   MODE tiles (W = 4, 8 or 16): each packet is a tile of the view's grid, 4 x 4 rays at
 *             W 16, 2 x 4 at 8, 2 x 2 at 4, row-major over tiles; a tile cut by the grid's
 *             right or bottom edge packs its rays into the first lanes and masks the rest.
 *             Each ray's primID (-1 on a miss) and tfar (inf) are written at its own
 *             index, as meshladar's cast writes them; hits and the primID sum are counted
 *             from them after the timing, and PRIMS.bin, if given, receives the primIDs
 *             (int32, every view's rays in turn).
 * Prints: width, the best pass's seconds, Mrays/s, hits and the sum of hit primIDs.
 */
#include <embree4/rtcore.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "common.h"

/* The rays of every view in RAYS.bin (p just after nviews: see the header comment); exits
 * if a view's rays do not fill its rows. */
static int64_t count_rays(const char *p, int64_t nviews) {
  int64_t total = 0;
  for (int64_t view = 0; view < nviews; view++) {
    int64_t n = *(const int64_t *)p, cols = *(const int64_t *)(p + 8);
    if (cols <= 0 || n % cols) {
      fprintf(stderr, "view %lld: %lld rays in rows of %lld\n", (long long)view, (long long)n,
              (long long)cols);
      exit(2);
    }
    total += n;
    p += 28 + 12 * n;
  }
  return total;
}

/* Lane k of the packet rh: ray i, from o[i] along d, t from 0 to inf, no hit yet. */
#define SET_LANE(k, i)                                                                      \
  rh.ray.org_x[k] = o[3 * (i)]; rh.ray.org_y[k] = o[3 * (i) + 1];                           \
  rh.ray.org_z[k] = o[3 * (i) + 2];                                                         \
  rh.ray.dir_x[k] = d[0]; rh.ray.dir_y[k] = d[1]; rh.ray.dir_z[k] = d[2];                   \
  rh.ray.tnear[k] = 0.0f; rh.ray.tfar[k] = INFINITY; rh.ray.time[k] = 0.0f;                 \
  rh.ray.mask[k] = 0xffffffffu; rh.ray.id[k] = 0; rh.ray.flags[k] = 0;                      \
  rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;                                               \
  rh.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;

/* Rows: rays s.. s + W - 1 per packet; masked lanes repeat ray s. */
#define PACKET_LOOP(W, RAYHIT, INTERSECT)                                                   \
  {                                                                                         \
    RAYHIT rh __attribute__((aligned(64)));                                                 \
    int valid[W] __attribute__((aligned(64)));                                              \
    for (int64_t s = 0; s < n; s += W) {                                                    \
      int64_t m = n - s < W ? n - s : W;                                                    \
      for (int k = 0; k < W; k++) {                                                         \
        int64_t i = s + (k < m ? k : 0);                                                    \
        valid[k] = k < m ? -1 : 0;                                                          \
        SET_LANE(k, i)                                                                      \
      }                                                                                     \
      INTERSECT(valid, scene, &rh, &args);                                                  \
      for (int k = 0; k < m; k++)                                                           \
        if (rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID) { hits++; prims += rh.hit.primID[k]; } \
    }                                                                                       \
  }

/* Tiles: TH x TW rays of the grid (rows of cols rays) per packet, idx[k] lane k's ray;
 * masked lanes repeat the tile's first ray. Results go to prim[i], tfar[i]. */
#define TILE_LOOP(W, TH, TW, RAYHIT, INTERSECT)                                             \
  {                                                                                         \
    RAYHIT rh __attribute__((aligned(64)));                                                 \
    int valid[W] __attribute__((aligned(64)));                                              \
    int64_t idx[W], rows = n / cols;                                                        \
    for (int64_t a0 = 0; a0 < rows; a0 += TH)                                               \
      for (int64_t b0 = 0; b0 < cols; b0 += TW) {                                           \
        int m = 0;                                                                          \
        for (int64_t a = a0; a < a0 + TH && a < rows; a++)                                  \
          for (int64_t b = b0; b < b0 + TW && b < cols; b++) idx[m++] = a * cols + b;       \
        for (int k = 0; k < W; k++) {                                                       \
          int64_t i = idx[k < m ? k : 0];                                                   \
          valid[k] = k < m ? -1 : 0;                                                        \
          SET_LANE(k, i)                                                                    \
        }                                                                                   \
        INTERSECT(valid, scene, &rh, &args);                                                \
        for (int k = 0; k < m; k++) {                                                       \
          int hit = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;                            \
          prim[idx[k]] = hit ? (int32_t)rh.hit.primID[k] : -1;                              \
          tfar[idx[k]] = hit ? rh.ray.tfar[k] : INFINITY;                                   \
        }                                                                                   \
      }                                                                                     \
  }

int main(int argc, char **argv) {
  if (argc < 6 || argc > 7) {
    fprintf(stderr, "usage: packets MESH.bin RAYS.bin WIDTH REPEATS rows|tiles [PRIMS.bin]\n");
    return 2;
  }
  size_t msize, rsize;
  char *mesh = slurp(argv[1], &msize), *rays = slurp(argv[2], &rsize);
  int width = atoi(argv[3]), repeats = atoi(argv[4]), tiles = !strcmp(argv[5], "tiles");
  if (!tiles && strcmp(argv[5], "rows")) { fprintf(stderr, "MODE: rows or tiles\n"); return 2; }
  if (tiles && width == 1) { fprintf(stderr, "tiles need a width of 4, 8 or 16\n"); return 2; }
  if (!tiles && argc == 7) { fprintf(stderr, "PRIMS.bin needs tiles\n"); return 2; }

  RTCDevice dev = rtcNewDevice(NULL);
  RTCScene scene = mesh_scene(dev, mesh);

  struct RTCIntersectArguments args;
  rtcInitIntersectArguments(&args);
  args.flags = RTC_RAY_QUERY_FLAG_COHERENT;
  int64_t nviews = ((int64_t *)rays)[0], total = 0, hits = 0, prims = 0;
  int64_t all = count_rays(rays + 8, nviews);
  int32_t *prim_all = malloc(sizeof(int32_t) * all);   /* the tiles' results (rows leave */
  float *tfar_all = malloc(sizeof(float) * all);        /* them untouched, unmapped) */
  double best = 1e300;
  for (int r = 0; r < repeats; r++) {
    hits = prims = total = 0;
    char *p = rays + 8;
    double t0 = now();
    for (int64_t view = 0; view < nviews; view++) {
      int64_t n = *(int64_t *)p, cols = *(int64_t *)(p + 8);
      const float *d = (const float *)(p + 16), *o = (const float *)(p + 28);
      int32_t *prim = prim_all + total;
      float *tfar = tfar_all + total;
      p += 28 + 12 * n;
      total += n;
      if (tiles && width == 16) TILE_LOOP(16, 4, 4, struct RTCRayHit16, rtcIntersect16)
      else if (tiles && width == 8) TILE_LOOP(8, 2, 4, struct RTCRayHit8, rtcIntersect8)
      else if (tiles) TILE_LOOP(4, 2, 2, struct RTCRayHit4, rtcIntersect4)
      else if (width == 16) PACKET_LOOP(16, struct RTCRayHit16, rtcIntersect16)
      else if (width == 8) PACKET_LOOP(8, struct RTCRayHit8, rtcIntersect8)
      else if (width == 4) PACKET_LOOP(4, struct RTCRayHit4, rtcIntersect4)
      else {
        struct RTCRayHit rh __attribute__((aligned(64)));
        for (int64_t i = 0; i < n; i++) {
          rh.ray.org_x = o[3 * i]; rh.ray.org_y = o[3 * i + 1]; rh.ray.org_z = o[3 * i + 2];
          rh.ray.dir_x = d[0]; rh.ray.dir_y = d[1]; rh.ray.dir_z = d[2];
          rh.ray.tnear = 0.0f; rh.ray.tfar = INFINITY; rh.ray.time = 0.0f;
          rh.ray.mask = 0xffffffffu; rh.ray.id = 0; rh.ray.flags = 0;
          rh.hit.geomID = rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
          rtcIntersect1(scene, &rh, &args);
          if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) { hits++; prims += rh.hit.primID; }
        }
      }
    }
    double t = now() - t0;
    if (t < best) best = t;
    for (int64_t i = 0; tiles && i < total; i++)      /* the tiles' checksum, untimed */
      if (prim_all[i] >= 0) { hits++; prims += prim_all[i]; }
  }
  if (argc == 7) {
    FILE *f = fopen(argv[6], "wb");
    if (!f || fwrite(prim_all, sizeof(int32_t), all, f) != (size_t)all || fclose(f)) {
      perror(argv[6]);
      return 2;
    }
  }
  printf("%d %.6f %.3f %lld %lld\n", width, best, total / best / 1e6, (long long)hits,
         (long long)prims);
  free(prim_all);
  free(tfar_all);
  rtcReleaseScene(scene);
  rtcReleaseDevice(dev);
  return 0;
}
