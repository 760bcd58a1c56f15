/* Exact distances of grid nodes to a mesh's triangles, near each triangle
 * (dynfab/geometry/triangle_band.py builds and calls it; the numpy fallback there is the
 * same computation).
 *
 * For every triangle t and every node g = origin + h (i, j, k) in t's bounding box grown by
 * `band` (clipped to the grid), exact[i, j, k] = min(exact[i, j, k], d(g, t)) with d the
 * Euclidean distance of a point to a triangle [m]: the closest point found by the Voronoi
 * region of the triangle it lies in (vertex, edge or face). `exact` is C-ordered (k fastest)
 * and holds +inf where no triangle reached. */

#include <math.h>

static double dynfab_dot(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Squared distance of p to the triangle (a, b, c). */
static double dynfab_triangle_distance2(const double* p, const double* a, const double* b, const double* c) {
  double ab[3], ac[3], ap[3], bp[3], cp[3], q[3];
  for (int x = 0; x < 3; ++x) {
    ab[x] = b[x] - a[x];
    ac[x] = c[x] - a[x];
    ap[x] = p[x] - a[x];
    bp[x] = p[x] - b[x];
    cp[x] = p[x] - c[x];
  }
  const double d1 = dynfab_dot(ab, ap), d2 = dynfab_dot(ac, ap);
  const double d3 = dynfab_dot(ab, bp), d4 = dynfab_dot(ac, bp);
  const double d5 = dynfab_dot(ab, cp), d6 = dynfab_dot(ac, cp);
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  if (d1 <= 0.0 && d2 <= 0.0) {
    for (int x = 0; x < 3; ++x) q[x] = a[x];
  } else if (d3 >= 0.0 && d4 <= d3) {
    for (int x = 0; x < 3; ++x) q[x] = b[x];
  } else if (d6 >= 0.0 && d5 <= d6) {
    for (int x = 0; x < 3; ++x) q[x] = c[x];
  } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double t = d1 / (d1 - d3);
    for (int x = 0; x < 3; ++x) q[x] = a[x] + t * ab[x];
  } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double t = d2 / (d2 - d6);
    for (int x = 0; x < 3; ++x) q[x] = a[x] + t * ac[x];
  } else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    for (int x = 0; x < 3; ++x) q[x] = b[x] + t * (c[x] - b[x]);
  } else {
    const double sum = va + vb + vc;
    const double v = sum != 0.0 ? vb / sum : 0.0, w = sum != 0.0 ? vc / sum : 0.0;
    for (int x = 0; x < 3; ++x) q[x] = a[x] + v * ab[x] + w * ac[x];
  }
  double d2sum = 0.0;
  for (int x = 0; x < 3; ++x) d2sum += (p[x] - q[x]) * (p[x] - q[x]);
  return d2sum;
}

void dynfab_triangle_band(const double* triangles, int count, const double* origin, double h, const int* shape,
                          double band, double* exact) {
  for (int t = 0; t < count; ++t) {
    const double* a = triangles + 9 * t;
    int first[3], last[3];
    for (int x = 0; x < 3; ++x) {
      const double low = fmin(a[x], fmin(a[3 + x], a[6 + x])) - band;
      const double high = fmax(a[x], fmax(a[3 + x], a[6 + x])) + band;
      first[x] = (int)floor((low - origin[x]) / h);
      last[x] = (int)ceil((high - origin[x]) / h);
      if (first[x] < 0) first[x] = 0;
      if (last[x] > shape[x] - 1) last[x] = shape[x] - 1;
    }
    for (int i = first[0]; i <= last[0]; ++i) {
      for (int j = first[1]; j <= last[1]; ++j) {
        double* row = exact + ((long)i * shape[1] + j) * shape[2];
        for (int k = first[2]; k <= last[2]; ++k) {
          const double p[3] = {origin[0] + h * i, origin[1] + h * j, origin[2] + h * k};
          const double d = sqrt(dynfab_triangle_distance2(p, a, a + 3, a + 6));
          if (d < row[k]) row[k] = d;
        }
      }
    }
  }
}
