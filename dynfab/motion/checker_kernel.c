/* dynfab's configuration checker kernel (dynfab/motion/checker_library.py builds it).
 *
 * Appended to CasADi's generated code of `centres` (q -> the k collision-sphere centres,
 * 3k numbers, column-major k x 3) and to the robot's constants (DYNFAB_DOF,
 * DYNFAB_SPHERES, DYNFAB_PAIRS, dynfab_radii[], dynfab_pairs[], DYNFAB_SZ_*), it gives
 *
 *   c_obs(q)  = min_{i,k} d_k(R_k^T (p_i(q) - c_k)) - r_i             [m]
 *   c_self(q) = min_{(a,b)} |p_a(q) - p_b(q)| - r_a - r_b               [m]
 *
 * with a broad phase: a sphere i and an obstacle k with bounding radius B_k are skipped
 * when |p_i - c_k| - r_i - B_k exceeds the threshold that still matters (the smallest
 * clearance so far, or the margin when only validity is asked), which cannot change the
 * result. An obstacle row has 17 numbers: kind (0 sphere, 1 box, 2 cylinder, 3 capsule,
 * 4 plane), centre (3), rotation R row-major (9), dimensions (3), bounding radius
 * (a plane: ignored).
 */

#define DYNFAB_ROW 17

static double dynfab_max(double a, double b) { return a > b ? a : b; }

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
  double best = INFINITY;
  for (int k = 0; k < n_obstacles && !(stop && best < margin); ++k) {
    const double* o = obstacles + DYNFAB_ROW * k;
    const int plane = (int)o[0] == 4;
    for (int i = 0; i < DYNFAB_SPHERES; ++i) {
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
  out[0] = best;
  double self_best = INFINITY;
  if (!(stop && best < margin)) {
    for (int j = 0; j < DYNFAB_PAIRS; ++j) {
      const int a = dynfab_pairs[2 * j], b = dynfab_pairs[2 * j + 1];
      const double dx = p_all[a] - p_all[b];
      const double dy = p_all[DYNFAB_SPHERES + a] - p_all[DYNFAB_SPHERES + b];
      const double dz = p_all[2 * DYNFAB_SPHERES + a] - p_all[2 * DYNFAB_SPHERES + b];
      const double c = sqrt(dx * dx + dy * dy + dz * dz) - dynfab_radii[a] - dynfab_radii[b];
      if (c < self_best) self_best = c;
      if (stop && self_best < self_margin) break;
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
