/* A native C reference for meshladar's packet backend: the same Embree 4 library (the one
 * the embreex wheel ships), the same shared-buffer scene, the same rays, cast in coherent
 * packets of width W (1, 4, 8 or 16) by a plain C loop. Built and run by native.py, which
 * times it against meshladar's numba loop on the same rays, interleaved.
 *
 *   packets MESH.bin RAYS.bin WIDTH REPEATS
 *   MESH.bin: int64 nv, int64 nf, float32 vertices[nv + 1][3] (one padding row),
 *             uint32 faces[nf][3]
 *   RAYS.bin: int64 nviews; per view: int64 n, float32 direction[3], float32 origins[n][3]
 * Prints: width, the best pass's seconds, Mrays/s, hits and the sum of hit primIDs.
 */
#include <embree4/rtcore.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static void *slurp(const char *path, size_t *size) {
  FILE *f = fopen(path, "rb");
  if (!f) { perror(path); exit(2); }
  fseek(f, 0, SEEK_END);
  *size = (size_t)ftell(f);
  fseek(f, 0, SEEK_SET);
  void *buf = aligned_alloc(64, (*size + 63) / 64 * 64);
  if (fread(buf, 1, *size, f) != *size) { perror(path); exit(2); }
  fclose(f);
  return buf;
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

#define PACKET_LOOP(W, RAYHIT, INTERSECT)                                                   \
  {                                                                                         \
    RAYHIT rh __attribute__((aligned(64)));                                                 \
    int valid[W] __attribute__((aligned(64)));                                              \
    for (int64_t s = 0; s < n; s += W) {                                                    \
      int64_t m = n - s < W ? n - s : W;                                                    \
      for (int k = 0; k < W; k++) {                                                         \
        int64_t i = s + (k < m ? k : 0);                                                    \
        valid[k] = k < m ? -1 : 0;                                                          \
        rh.ray.org_x[k] = o[3 * i]; rh.ray.org_y[k] = o[3 * i + 1];                         \
        rh.ray.org_z[k] = o[3 * i + 2];                                                     \
        rh.ray.dir_x[k] = d[0]; rh.ray.dir_y[k] = d[1]; rh.ray.dir_z[k] = d[2];             \
        rh.ray.tnear[k] = 0.0f; rh.ray.tfar[k] = INFINITY; rh.ray.time[k] = 0.0f;           \
        rh.ray.mask[k] = 0xffffffffu; rh.ray.id[k] = 0; rh.ray.flags[k] = 0;                \
        rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;                                         \
        rh.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;                                         \
      }                                                                                     \
      INTERSECT(valid, scene, &rh, &args);                                                  \
      for (int k = 0; k < m; k++)                                                           \
        if (rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID) { hits++; prims += rh.hit.primID[k]; } \
    }                                                                                       \
  }

int main(int argc, char **argv) {
  if (argc != 5) { fprintf(stderr, "usage: packets MESH.bin RAYS.bin WIDTH REPEATS\n"); return 2; }
  size_t msize, rsize;
  char *mesh = slurp(argv[1], &msize), *rays = slurp(argv[2], &rsize);
  int width = atoi(argv[3]), repeats = atoi(argv[4]);
  int64_t nv = ((int64_t *)mesh)[0], nf = ((int64_t *)mesh)[1];
  float *vert = (float *)(mesh + 16);
  uint32_t *faces = (uint32_t *)(mesh + 16 + 12 * (nv + 1));

  RTCDevice dev = rtcNewDevice(NULL);
  RTCScene scene = rtcNewScene(dev);
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vert, 0, 12, nv);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, faces, 0, 12, nf);
  rtcCommitGeometry(g);
  rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
  rtcCommitScene(scene);
  if (rtcGetDeviceError(dev) != RTC_ERROR_NONE) { fprintf(stderr, "embree error\n"); return 1; }

  struct RTCIntersectArguments args;
  rtcInitIntersectArguments(&args);
  args.flags = RTC_RAY_QUERY_FLAG_COHERENT;
  int64_t nviews = ((int64_t *)rays)[0], total = 0, hits = 0, prims = 0;
  double best = 1e300;
  for (int r = 0; r < repeats; r++) {
    hits = prims = total = 0;
    char *p = rays + 8;
    double t0 = now();
    for (int64_t view = 0; view < nviews; view++) {
      int64_t n = *(int64_t *)p;
      const float *d = (const float *)(p + 8), *o = (const float *)(p + 20);
      p += 20 + 12 * n;
      total += n;
      if (width == 16) PACKET_LOOP(16, struct RTCRayHit16, rtcIntersect16)
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
  }
  printf("%d %.6f %.3f %lld %lld\n", width, best, total / best / 1e6, (long long)hits,
         (long long)prims);
  rtcReleaseScene(scene);
  rtcReleaseDevice(dev);
  return 0;
}
