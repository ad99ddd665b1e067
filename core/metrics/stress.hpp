#pragma once
// The stress a packing carries through its contacts (Love-Weber; e.g. Christoffersen, Mehrabadi
// and Nemat-Nasser, J. Appl. Mech. 48 (1981) 339): over a volume V,
//   sigma_ab = (1 / V) sum over contacts c of f_a^c l_b^c,
// f^c the force on the second body of the pair, l^c the branch vector from the first body's
// centre (a clump's centre of mass) to the second's (minimum image). Compression is positive. The
// kinetic part rho <v v> is left out: the lab tests read quasi-static beds.
#include <array>

#include "core/sim/world.hpp"

namespace demcal::metrics {

using Tensor3 = std::array<std::array<double, 3>, 3>;

/// The contact stress of the particle-particle contacts of the world's neighbour list (walls
/// excluded) over `volume` (m^3, e.g. a periodic cell's). Each listed pair's law is evaluated
/// again on a copy of its history with a time step of 0, so the tangential springs are read as
/// they stand and nothing in the world changes.
Tensor3 contact_stress(const sim::World& world, double volume);

/// p = trace / 3 (Pa).
double mean_stress(const Tensor3& s);
/// The deviatoric invariant q = sqrt(3 J2) (Pa): for an axisymmetric state, |sigma_1 - sigma_3|.
double deviatoric_stress(const Tensor3& s);

}  // namespace demcal::metrics
