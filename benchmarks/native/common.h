/* What packets.c and limit.c share: reading a whole input file into 64-byte-aligned memory,
 * and a monotonic clock in seconds. */
#ifndef MESHLADAR_NATIVE_COMMON_H
#define MESHLADAR_NATIVE_COMMON_H
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

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
#endif
