// Speed and correctness reference for the onboard ESDF: a full DynamicEDT3D (libdynamicedt3d-dev, Lau et al.)
// distance transform of an occupancy grid written by `tetherbot edt-bench`.
// Input: u32 n (little-endian), then n^3 bytes (1 = occupied), x fastest. Optional second argument: a file to
// which the distances (float32, cell units, same order) are written.
// Output on stdout: "ms=<init+update wall ms> cpu_ms=<thread CPU ms> occupied=<count> sum=<sum of distances>".
// CPU time is the fair figure on a loaded machine.
#include <dynamicEDT3D/dynamicEDT3D.h>
#include <chrono>
#include <ctime>
#include <cstdint>
#include <cstdio>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 2) { std::fprintf(stderr, "usage: edt3d GRID [DISTANCES_OUT]\n"); return 2; }
  std::FILE* f = std::fopen(argv[1], "rb");
  if (!f) { std::perror(argv[1]); return 2; }
  uint32_t n = 0;
  if (std::fread(&n, 4, 1, f) != 1 || n == 0 || n > 1024) { std::fprintf(stderr, "bad header\n"); return 2; }
  std::vector<unsigned char> occ(size_t(n) * n * n);
  if (std::fread(occ.data(), 1, occ.size(), f) != occ.size()) { std::fprintf(stderr, "short grid\n"); return 2; }
  std::fclose(f);
  // bool*** allocated with new[] at every level: DynamicEDT3D takes ownership and deletes it.
  bool*** grid = new bool**[n];
  size_t occupied = 0;
  for (uint32_t x = 0; x < n; ++x) {
    grid[x] = new bool*[n];
    for (uint32_t y = 0; y < n; ++y) {
      grid[x][y] = new bool[n];
      for (uint32_t z = 0; z < n; ++z) {
        bool o = occ[x + size_t(n) * (y + size_t(n) * z)] != 0;
        grid[x][y][z] = o;
        occupied += o;
      }
    }
  }
  const int maxdist = 127;  // same cap as the onboard ESDF (site offsets are i8)
  timespec c0, c1;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
  auto t0 = std::chrono::steady_clock::now();
  DynamicEDT3D edt(maxdist * maxdist);
  edt.initializeMap(n, n, n, grid);
  edt.update(true);
  auto t1 = std::chrono::steady_clock::now();
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
  double cpu_ms = (c1.tv_sec - c0.tv_sec) * 1e3 + (c1.tv_nsec - c0.tv_nsec) / 1e6;
  double ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  double sum = 0;
  std::vector<float> dist(occ.size());
  for (uint32_t z = 0; z < n; ++z)
    for (uint32_t y = 0; y < n; ++y)
      for (uint32_t x = 0; x < n; ++x) {
        float d = edt.getDistance(x, y, z);
        dist[x + size_t(n) * (y + size_t(n) * z)] = d;
        sum += d;
      }
  if (argc > 2) {
    std::FILE* o = std::fopen(argv[2], "wb");
    if (!o) { std::perror(argv[2]); return 2; }
    std::fwrite(dist.data(), sizeof(float), dist.size(), o);
    std::fclose(o);
  }
  std::printf("ms=%.3f cpu_ms=%.3f occupied=%zu sum=%.3f\n", ms, cpu_ms, occupied, sum);
  return 0;
}
