#pragma once
// The specular manifold of a path (Jakob and Marschner 2012, "Manifold Exploration", section 4):
// a chain of vertices x_a .. x_b whose inner vertices x_{a+1} .. x_{b-1} are specular satisfies,
// at each inner vertex i, the constraint that the generalized half vector
//   h_i = eta_i w_i + eta_o w_o   (w_i, w_o the unit directions to x_{i-1} and x_{i+1}, eta the
//                                  indices of refraction on their sides; both 1 for reflection)
// is parallel to the shading normal: c_i = (s_i . h_i, t_i . h_i) = 0 in a tangent frame of it.
// Each c_i depends on three vertices only, so the derivative of the stacked constraints with
// respect to the vertices' tangent-plane coordinates is block tridiagonal (2 x 2 blocks). Holding
// one end of the chain and moving the other, the implicit function theorem gives how the inner
// vertices follow; that is the manifold walk's Newton step and the generalized geometry term
// that the manifold perturbation's transition density carries.
//
// Coordinates: each vertex moves in the tangent plane of its surface, in the orthonormal basis
// (dpdu, dpdv) of Scene::surfaceDifferential, so that a 2 x 2 determinant is a ratio of areas.
// The derivatives are those at a chain that satisfies its constraints (ray tracing through the
// specular vertices makes such chains), where the turning of the tangent frame enters only
// through the shading normal's derivative.
#include "common/transport/path.h"

namespace farm {

class Scene;

struct Matrix2 {
  double m[2][2] = {{0, 0}, {0, 0}};
  double determinant() const { return m[0][0] * m[1][1] - m[0][1] * m[1][0]; }
};

// Whether x_a .. x_b is a specular chain the walk can move: a + 1 < b, inner vertices specular
// surface vertices whose triangles are known, x_b a non-specular surface vertex, x_a a
// non-specular vertex at a finite point (a surface, an area light or a point light).
bool isSpecularChain(const Scene& scene, const Path& x, int a, int b);

// With x_a held, the derivative of x_{a+1}'s tangent coordinates with respect to x_b's
// (moveEnd), or with x_b held, of x_{b-1}'s with respect to x_a's (!moveEnd; x_a must then be a
// surface vertex). False where the constraints' Jacobian is singular or the chain is not one.
bool specularChainDerivative(const Scene& scene, const Path& x, int a, int b, bool moveEnd,
                             Matrix2* derivative);

// The solid angle per unit area that the chain maps between its ends: with x_a held, the
// directions leaving x_a towards x_{a+1} per unit area of x_b, |d omega_a / dA_b| (moveEnd);
// or with x_b held, |d omega_b / dA_a|. Through no specular vertex it would be cos / d^2. For
// reciprocity, eta_a^2 |cos_a| |d omega_a / dA_b| = eta_b^2 |cos_b| |d omega_b / dA_a| (etendue).
// 0 where the derivative does not exist.
double chainSolidAnglePerArea(const Scene& scene, const Path& x, int a, int b, bool moveEnd);

// log of the ratio between Path's measurement contribution of x and the contribution with the
// chain's specular vertices integrated out (x_a and x_b area-measured, the generalized geometry
// term in place of the chain): Path's convention keeps each specular vertex area-measured with
// the coefficient of its delta function, so this is
//   prod_{j=a+1}^{b-1} [cos_{j+1} / d_{j,j+1}^2  *  d omega_{to x_{j-1}} / d omega_{to x_{j+1}}]
//   / |det (d u_{a+1} / d u_b)|,
// the density that tracing from x_a through the chain gives x_b in Path's convention, over the
// true one (the same direction density times |d omega_a / dA_b|). A perturbation that places the
// chain by a manifold walk instead of by sampling multiplies its density by this, so that the
// acceptance compares contributions in one measure. -infinity where it does not exist.
double logSpecularChainMeasureRatio(const Scene& scene, const Path& x, int a, int b);

}  // namespace farm
