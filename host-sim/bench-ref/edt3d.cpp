// Speed and correctness reference for the onboard ESDF: a full DynamicEDT3D (libdynamicedt3d-dev, Lau et al.)
// distance transform of an occupancy grid written by `tetherbot edt-bench`.
// Input: u32 n (little-endian), then n^3 bytes (1 = occupied), x fastest. Optional second argument: a file to
// which the distances (float32, cell units, same order) are written.
// Output on stdout: "ms=<init+update milliseconds> occupied=<count> sum=<sum of distances>".
#include <dynamicEDT3D/dynamicEDT3D.h>
#include <chrono>
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
  // bool*** as the library wants it.
  std::vector<bool*> rows(size_t(n) * n);
  std::vector<bool**> planes(n);
  std::vector<bool> dummy;
  bool* cells = new bool[occ.size()];
  size_t occupied = 0;
  // gridMap[x][y][z]
  for (uint32_t x = 0; x < n; ++x) {
    planes[x] = &rows[size_t(x) * n];
    for (uint32_t y = 0; y < n; ++y) {
      rows[size_t(x) * n + y] = &cells[(size_t(x) * n + y) * n];
      for (uint32_t z = 0; z < n; ++z) {
        bool o = occ[x + size_t(n) * (y + size_t(n) * z)] != 0;
        cells[(size_t(x) * n + y) * n + z] = o;
        occupied += o;
      }
    }
  }
  const int maxdist = 127;  // same cap as the onboard ESDF (site offsets are i8)
  auto t0 = std::chrono::steady_clock::now();
  DynamicEDT3D edt(maxdist * maxdist);
  edt.initializeMap(n, n, n, planes.data());
  edt.update(true);
  auto t1 = std::chrono::steady_clock::now();
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
  std::printf("ms=%.3f occupied=%zu sum=%.3f\n", ms, occupied, sum);
  delete[] cells;
  return 0;
}
