// The classic sequential PBD loop over a constraint batch: the reference the parallel solver
// modes are compared against, for results and for speed.
//
// One thread, the constraints of [begin, end) in input order, each projected by the scalar
// API (tessera::PositionBasedDynamics, tessera::XPBD) on the positions as they are at that
// moment, and its corrections added to its movable particles before the next constraint is
// evaluated (Gauss–Seidel in input order), as the classic PBD library's solver loop does.
// Unlike the batched kernels (project_<family>_constraints), the constraints of a range may
// share particles freely: no colouring is needed.
//
// Every family has one overload, declared with the family (<family>_constraints.hpp, where its
// comment names the scalar-API function and arguments it maps to). Every overload reads the batch's
// stored rest data and parameters exactly as the family's batched kernel interprets them, so on
// constraints that share no movable particle it gives the batched kernel's result up to rounding
// (the two evaluate the same formula, with different instruction sequences). Particles with inverse
// mass 0 are never written. Each overload checks the range and the particle count once
// (check_projection_range) and throws InvalidInput when they are wrong.
#pragma once

#include <tessera/core/constraint_families.hpp>
