// A start for the per-vertex design fit made from the measure itself (weighted_design.h), where no
// neighbour's design is close enough to refit. Private to the library.
#pragma once

#include "sdlighting/spherical_design.h"

#include <glm/vec3.hpp>

#include <vector>

namespace sd {

/// The index of the direction in `dirs` (non-empty, unit) nearest to the unit vector `dir`.
int nearest_direction(const glm::dvec3& dir, const std::vector<glm::dvec3>& dirs);

/// `count` clusters (at most one per direction) of the discrete measure Σ weights_i δ(dirs_i)
/// (unit directions, weights > 0): farthest-point seeds, then Lloyd iterations on the sphere; each
/// cluster becomes a node at its normalised weighted mean with the cluster's mass, so the weights
/// sum to the measure's mass and the nodes lie among its samples (a mean can fall off a non-convex
/// support, which the refit corrects). Not certified: method "clustered", residual unset.
SphericalDesign clustered_start(const std::vector<glm::dvec3>& dirs, const std::vector<double>& weights, int count,
                                int degree);

}  // namespace sd
