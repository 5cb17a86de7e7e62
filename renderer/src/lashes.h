#pragma once
// An eye's lashes (Lashes in appearance.h) as chains of capsules (internal
// to renderer/), rooted on the face mesh's margin edges: built per scene
// with the face, so that they follow the lids.
//
// A lash of length L leaves its root (on the margin's anterior edge, sunk
// by its radius into the skin so that no gap shows) in the plane of the
// skin's normal N and the lid's rise R (away from the opening), fanned
// toward the nearer canthus by up to 20 deg; its angle from N toward R
// runs linearly from -root_deg at the root to -root_deg + curl at the tip:
// an arc of constant curvature, cut into kLashSegments chords (a 9.5 mm
// lash bent 45 deg strays up to 0.026 mm from its arc, the chords'
// sagitta: a third of a headset pixel). Each chord is a capsule (a cylinder with hemispherical
// ends) of the mean radius over its length, tapering from the root's to a
// third of it at the tip in steps.
//
// Lashes cover the fissure coordinate u from -0.97 (lateral canthus) to
// 0.6 (the lacrimal punctum, some 6 mm from the medial canthus; no lashes
// grow medial to it), spaced evenly along the edge's length with jitter;
// length scales by 0.55 + 0.45 (1 - w^2), w running from -1 to 1 over the
// lashed part: longest at its middle. Jitter per lash, from the counter
// stream (seed, stream): place +-0.4 of the spacing, length +-12%, fan and
// root +-5 deg, curl +-20%.

#include <cstdint>
#include <vector>

#include "face_mesh.h"
#include "purkinje/models/appearance.h"

namespace purkinje::renderer {

inline constexpr int kLashSegments = 6;

struct HairSegment {
  Point3 a, b;  // the capsule's axis, world
  double radius_mm = 0;
};


// The lashes of one lid: `upper` picks the upper lid's numbers; `stream`
// separates the lids' (and eyes') draws.
std::vector<HairSegment> build_lashes(const Lashes& lashes, const MarginEdge& edge, bool upper, std::uint64_t stream);

}  // namespace purkinje::renderer
