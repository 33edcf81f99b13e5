/* Small deterministic linear algebra shared by probe placement and Delaunay. */
#ifndef BK_PROBE_MATH_H
#define BK_PROBE_MATH_H

#include <stddef.h>

/* Eigen-decomposition of the symmetric 3×3 matrix a (row-major) by cyclic Jacobi rotations.
 * values descending; vectors[k] is the unit eigenvector of values[k]. Each vector's sign is
 * fixed so that its largest-magnitude component is positive (the first one on ties), and then
 * vectors[2] = vectors[0] × vectors[1] (right-handed frame). Deterministic. */
void bk_sym3_eigen(const double a[9], double values[3], double vectors[3][3]);

/* Unit direction i of n spread evenly over the sphere (spherical Fibonacci), deterministic. */
void bk_sphere_direction(size_t i, size_t n, float dir[3]);

/* Triangle / axis-aligned box overlap (separating axis test, Akenine-Möller). */
int bk_tri_box_overlap(const double centre[3], const double half[3], const float *a,
                       const float *b, const float *c);
#endif
