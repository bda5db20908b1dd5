/* What packets.c and limit.c share: reading a whole input file into 64-byte-aligned memory,
 * a monotonic clock in seconds, and the robust Embree scene of MESH.bin's triangles. */
#ifndef MESHLADAR_NATIVE_COMMON_H
#define MESHLADAR_NATIVE_COMMON_H
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include <embree4/rtcore.h>

static void *slurp(const char *path, size_t *size) {
  FILE *f = fopen(path, "rb");
  if (!f) { perror(path); exit(2); }
  fseek(f, 0, SEEK_END);
  *size = (size_t)ftell(f);
  fseek(f, 0, SEEK_SET);
  void *buf = aligned_alloc(64, (*size + 63) / 64 * 64);
  if (!buf || fread(buf, 1, *size, f) != *size) { perror(path); exit(2); }
  fclose(f);
  return buf;
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* The committed robust scene of MESH.bin (int64 nv, int64 nf, float32 vertices[nv + 1][3],
 * uint32 faces[nf][3]), its buffers shared; exits on an Embree error. */
static RTCScene mesh_scene(RTCDevice dev, char *mesh) {
  int64_t nv = ((int64_t *)mesh)[0], nf = ((int64_t *)mesh)[1];
  RTCScene scene = rtcNewScene(dev);
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, mesh + 16, 0, 12,
                             nv);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                             mesh + 16 + 12 * (nv + 1), 0, 12, nf);
  rtcCommitGeometry(g);
  rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
  rtcCommitScene(scene);
  if (rtcGetDeviceError(dev) != RTC_ERROR_NONE) { fprintf(stderr, "embree error\n"); exit(1); }
  return scene;
}
#endif
