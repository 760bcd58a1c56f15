/* dynfab's configuration checker kernel (dynfab/motion/checker_library.py builds it).
 *
 * Appended to CasADi's generated code of `centres` (q -> the k collision-sphere centres,
 * 3k numbers, column-major k x 3) and to the robot's constants (DYNFAB_DOF,
 * DYNFAB_SPHERES, DYNFAB_PAIRS, dynfab_radii[], dynfab_pairs[], DYNFAB_SZ_*), it gives
 *
 *   c_obs(q)  = min_{i,k} d_k(R_k^T (p_i(q) - c_k)) - r_i             [m]
 *   c_self(q) = min_{(a,b)} |p_a(q) - p_b(q)| - r_a - r_b               [m]
 *
 * with i over the spheres some joint moves (a link whose dynfab_group_moves[g] is 0, the
 * base, is left out of c_obs: no configuration changes its clearance) and all spheres in
 * the self-collision pairs,
 * with a broad phase in two levels: a link's spheres (a group with the ball of radius R_g
 * about their centroid g holding them all) and an obstacle k with bounding radius B_k are
 * skipped when |g - c_k| - R_g - B_k exceeds the threshold that still matters (the
 * smallest clearance so far, or the margin when only validity is asked), and so is one
 * sphere i when |p_i - c_k| - r_i - B_k does; the self-collision pairs between two links
 * (a block) are skipped when the links' balls are farther apart than the threshold.
 * None of this can change the result. The groups and blocks come with the robot's
 * constants (DYNFAB_GROUPS, DYNFAB_BLOCKS, dynfab_group_*[], dynfab_block_*[]). An obstacle row has 17 numbers: kind (0 sphere, 1 box, 2 cylinder, 3 capsule,
 * 4 plane), centre (3), rotation R row-major (9), dimensions (3), bounding radius
 * (a plane: ignored). Kind 5 is a mesh's distance grid (dynfab/geometry/distance_grid.py): its
 * dimensions[0] is the offset, in doubles from the row's start, of the grid's data in the same
 * obstacle buffer (after the rows), and the distance is the grid's lower bound. Kind 6 is a
 * point cloud's grid (dynfab/geometry/cloud_grid.py), laid out and read the same.
 */

#define DYNFAB_ROW 17

static double dynfab_max(double a, double b) { return a > b ? a : b; }

/* Lower bound of the distance to a mesh or a cloud at a point (x, y, z) of its frame:
 * outside the grid the distance to the bounding box, inside max_j (v_j - |p - g_j|) over the
 * cell's corners g_j (node values v_j; each term is a lower bound alone: the distance is
 * 1-Lipschitz). Layout of
 * `grid`: nx, ny, nz, h, origin (3), box low (3), box high (3), then nx*ny*nz values, z
 * fastest. */
static double dynfab_grid_distance(const double* grid, double x, double y, double z) {
  const int n[3] = {(int)grid[0], (int)grid[1], (int)grid[2]};
  const double h = grid[3], p[3] = {x, y, z};
  double cell[3], gap2 = 0.0;
  int inside = 1, base[3];
  for (int a = 0; a < 3; ++a) {
    const double below = grid[7 + a] - p[a], above = p[a] - grid[10 + a];
    const double out = below > 0.0 ? below : (above > 0.0 ? above : 0.0);
    gap2 += out * out;
    cell[a] = (p[a] - grid[4 + a]) / h;
    if (!(cell[a] >= 0.0 && cell[a] <= (double)(n[a] - 1))) inside = 0;
  }
  if (!inside) return sqrt(gap2);
  for (int a = 0; a < 3; ++a) {
    base[a] = (int)cell[a];
    if (base[a] > n[a] - 2) base[a] = n[a] - 2;
    cell[a] -= (double)base[a];
  }
  const double* values = grid + 13;
  double best = -INFINITY;
  for (int c = 0; c < 8; ++c) {
    const int o[3] = {c >> 2 & 1, c >> 1 & 1, c & 1};
    double d2 = 0.0;
    for (int a = 0; a < 3; ++a) {
      const double d = (cell[a] - (double)o[a]) * h;
      d2 += d * d;
    }
    const long index = ((long)(base[0] + o[0]) * n[1] + (base[1] + o[1])) * n[2] + (base[2] + o[2]);
    best = dynfab_max(best, values[index] - sqrt(d2));
  }
  return best;
}

static double dynfab_distance(const double* o, const double* p) {
  const double dx = p[0] - o[1], dy = p[1] - o[2], dz = p[2] - o[3];
  const double* r = o + 4;
  const double x = r[0] * dx + r[3] * dy + r[6] * dz;
  const double y = r[1] * dx + r[4] * dy + r[7] * dz;
  const double z = r[2] * dx + r[5] * dy + r[8] * dz;
  const double* d = o + 13;
  switch ((int)o[0]) {
    case 0:
      return sqrt(x * x + y * y + z * z) - d[0];
    case 1: {
      const double ex = fabs(x) - 0.5 * d[0], ey = fabs(y) - 0.5 * d[1], ez = fabs(z) - 0.5 * d[2];
      const double ox = dynfab_max(ex, 0.0), oy = dynfab_max(ey, 0.0), oz = dynfab_max(ez, 0.0);
      const double inside = dynfab_max(ex, dynfab_max(ey, ez));
      return sqrt(ox * ox + oy * oy + oz * oz) + (inside < 0.0 ? inside : 0.0);
    }
    case 2: {
      const double radial = sqrt(x * x + y * y) - d[0], axial = fabs(z) - 0.5 * d[1];
      const double orad = dynfab_max(radial, 0.0), oax = dynfab_max(axial, 0.0);
      const double inside = dynfab_max(radial, axial);
      return sqrt(orad * orad + oax * oax) + (inside < 0.0 ? inside : 0.0);
    }
    case 3: {
      double a = z;
      if (a > 0.5 * d[1]) a = 0.5 * d[1];
      if (a < -0.5 * d[1]) a = -0.5 * d[1];
      return sqrt(x * x + y * y + (z - a) * (z - a)) - d[0];
    }
    case 5:
    case 6:
      return dynfab_grid_distance(o + (long)d[0], x, y, z);
    default:
      return z;
  }
}

/* Clearances of one configuration; with `stop` set, returns as soon as one of them is
 * below its margin (the values written are then only upper bounds). */
static void dynfab_one(const double* q, const double* obstacles, int n_obstacles, double margin,
                       double self_margin, int stop, double* out) {
  double p_all[3 * DYNFAB_SPHERES];
  const casadi_real* arg[DYNFAB_SZ_ARG > 1 ? DYNFAB_SZ_ARG : 1];
  casadi_real* res[DYNFAB_SZ_RES > 1 ? DYNFAB_SZ_RES : 1];
  casadi_int iw[DYNFAB_SZ_IW > 0 ? DYNFAB_SZ_IW : 1];
  casadi_real w[DYNFAB_SZ_W > 0 ? DYNFAB_SZ_W : 1];
  arg[0] = q;
  res[0] = p_all;
  centres(arg, res, iw, w, 0);
  double groups[3 * DYNFAB_GROUPS]; /* centroid of each link's sphere centres, a point fixed on the link */
  for (int g = 0; g < DYNFAB_GROUPS; ++g) {
    double sum[3] = {0.0, 0.0, 0.0};
    for (int m = dynfab_group_start[g]; m < dynfab_group_start[g + 1]; ++m)
      for (int a = 0; a < 3; ++a) sum[a] += p_all[a * DYNFAB_SPHERES + dynfab_group_spheres[m]];
    const double count = (double)(dynfab_group_start[g + 1] - dynfab_group_start[g]);
    for (int a = 0; a < 3; ++a) groups[3 * g + a] = sum[a] / count;
  }
  double best = INFINITY;
  for (int k = 0; k < n_obstacles && !(stop && best < margin); ++k) {
    const double* o = obstacles + DYNFAB_ROW * k;
    const int plane = (int)o[0] == 4;
    for (int g = 0; g < DYNFAB_GROUPS && !(stop && best < margin); ++g) {
      if (!dynfab_group_moves[g]) continue; /* the base: the same clearance at every configuration */
      if (!plane) { /* the link's bounding ball: all of its spheres, or none, can matter */
        const double reach = (stop ? margin : best) + dynfab_group_radius[g] + o[16];
        const double dx = groups[3 * g] - o[1], dy = groups[3 * g + 1] - o[2], dz = groups[3 * g + 2] - o[3];
        if (reach > 0.0 && dx * dx + dy * dy + dz * dz > reach * reach) continue;
      }
      for (int m = dynfab_group_start[g]; m < dynfab_group_start[g + 1]; ++m) {
        const int i = dynfab_group_spheres[m];
        const double p[3] = {p_all[i], p_all[DYNFAB_SPHERES + i], p_all[2 * DYNFAB_SPHERES + i]};
        if (!plane) {
          const double reach = (stop ? margin : best) + dynfab_radii[i] + o[16];
          const double dx = p[0] - o[1], dy = p[1] - o[2], dz = p[2] - o[3];
          if (reach > 0.0 && dx * dx + dy * dy + dz * dz > reach * reach) continue;
        }
        const double c = dynfab_distance(o, p) - dynfab_radii[i];
        if (c < best) best = c;
        if (stop && best < margin) break;
      }
    }
  }
  out[0] = best;
  double self_best = INFINITY;
  if (!(stop && best < margin)) {
    for (int blk = 0; blk < DYNFAB_BLOCKS && !(stop && self_best < self_margin); ++blk) {
      const int ga = dynfab_block_groups[2 * blk], gb = dynfab_block_groups[2 * blk + 1];
      const double reach = (stop ? self_margin : self_best) + dynfab_group_radius[ga] + dynfab_group_radius[gb];
      const double gx = groups[3 * ga] - groups[3 * gb], gy = groups[3 * ga + 1] - groups[3 * gb + 1],
                   gz = groups[3 * ga + 2] - groups[3 * gb + 2];
      if (reach > 0.0 && gx * gx + gy * gy + gz * gz > reach * reach) continue; /* the links' balls are apart */
      for (int j = dynfab_block_start[blk]; j < dynfab_block_start[blk + 1]; ++j) {
        const int a = dynfab_pairs[2 * j], b = dynfab_pairs[2 * j + 1];
        const double dx = p_all[a] - p_all[b];
        const double dy = p_all[DYNFAB_SPHERES + a] - p_all[DYNFAB_SPHERES + b];
        const double dz = p_all[2 * DYNFAB_SPHERES + a] - p_all[2 * DYNFAB_SPHERES + b];
        const double c = sqrt(dx * dx + dy * dy + dz * dz) - dynfab_radii[a] - dynfab_radii[b];
        if (c < self_best) self_best = c;
        if (stop && self_best < self_margin) break;
      }
    }
  }
  out[1] = self_best;
}

/* Clearances (count x 2) of `count` configurations (count x DYNFAB_DOF, row-major). */
CASADI_SYMBOL_EXPORT void dynfab_clearances(const double* qs, int count, const double* obstacles, int n_obstacles,
                                            double* out) {
  for (int c = 0; c < count; ++c) dynfab_one(qs + DYNFAB_DOF * c, obstacles, n_obstacles, 0.0, 0.0, 0, out + 2 * c);
}

/* Index of the first of `count` configurations that is not free (a clearance below its
 * margin), or -1 if all are. */
CASADI_SYMBOL_EXPORT int dynfab_first_blocked(const double* qs, int count, const double* obstacles, int n_obstacles,
                                              double margin, double self_margin) {
  double out[2];
  for (int c = 0; c < count; ++c) {
    dynfab_one(qs + DYNFAB_DOF * c, obstacles, n_obstacles, margin, self_margin, 1, out);
    if (out[0] < margin || out[1] < self_margin) return c;
  }
  return -1;
}

/* Checks the straight motion from `a` to `b` (DYNFAB_DOF each) at configurations at most
 * `step` apart (Euclidean, joint space): `b` first, then the inner configurations coarse
 * to fine (every 2^k-th before the ones between them), so that a blocked motion is
 * usually found after a few checks. `a` is not checked (the planner's motions start at a
 * free configuration). Returns the number of configurations checked, negated if the last
 * of them is not free (the motion is blocked). */
CASADI_SYMBOL_EXPORT int dynfab_motion_free(const double* a, const double* b, double step, const double* obstacles,
                                            int n_obstacles, double margin, double self_margin) {
  double out[2], q[DYNFAB_DOF], length2 = 0.0;
  int checked = 1;
  dynfab_one(b, obstacles, n_obstacles, margin, self_margin, 1, out);
  if (out[0] < margin || out[1] < self_margin) return -checked;
  for (int j = 0; j < DYNFAB_DOF; ++j) length2 += (b[j] - a[j]) * (b[j] - a[j]);
  const int count = (int)ceil(sqrt(length2) / step);
  int stride = 1;
  while (2 * stride < count) stride *= 2;
  for (; stride >= 1; stride /= 2) {
    for (int i = stride; i < count; i += 2 * stride) { /* odd multiples of stride: new at this level */
      const double f = (double)i / count;
      for (int j = 0; j < DYNFAB_DOF; ++j) q[j] = a[j] + f * (b[j] - a[j]);
      ++checked;
      dynfab_one(q, obstacles, n_obstacles, margin, self_margin, 1, out);
      if (out[0] < margin || out[1] < self_margin) return -checked;
    }
  }
  return checked;
}
