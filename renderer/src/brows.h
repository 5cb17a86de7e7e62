#pragma once
// An eye's brows (Brows in appearance.h) as hairs of capsules (internal to
// renderer/), rooted on the face mesh: built per scene with the face.
//
// The band, in the head frame's nasal coordinate n and height y: from its
// head above the medial canthus (n = eyelids.half_width_mm) to its tail
// 14 mm past the lateral canthus (n = -lateral_canthus_mm - 14), at
// fraction s of the way its lower edge at height_mm + 2.5 (1 - ((s -
// 0.65) / 0.65)^2) (the arch's top above the lateral limbus) and its
// height width_mm (1 - 0.6 s). Roots are drawn uniformly over the band
// (hairs_per_mm2 times its area of them), thinned where it is feathered
// (kept with probability smoothstep(s; -0.02, 0.15) times smoothstep(e;
// -0.1, 0.2), e the distance from the nearer edge as a fraction of the
// band's height: no hard outline), and set on the mesh where a ray
// along the head's -z meets it (its front-most triangle); each hair
// leaves the skin lift_deg above the skin's tangent plane in the
// direction of growth, bends toward the skin by curl_deg (at most back to
// that plane), and is cut into kBrowSegments chords (an 8 mm hair bent 20
// deg strays about 0.02 mm from its arc). Growth, as seen from the front
// (angle above the lateral direction): 80 deg (up) at the head, turning
// over the first quarter to the body's +-20 deg (the band's lower edge
// tipped up, its upper edge down, meeting along the middle), and over
// the last quarter to -20 deg (down) at the tail. Jitter per hair, from
// the counter stream (seed, stream): growth +-12 deg, lift +-5 deg,
// length +-20%, curl +-30%.

#include <cstdint>
#include <vector>

#include "face_mesh.h"
#include "lashes.h"
#include "purkinje/models/appearance.h"

namespace purkinje::renderer {

inline constexpr int kBrowSegments = 4;

// The brows of one eye's face: `mesh` is that face, `world_from_head` its
// head frame; `stream` separates the eyes' draws.
std::vector<HairSegment> build_brows(const Brows& brows, const Eyelids& lids, const Face& face, const FaceMesh& mesh,
                                     const Pose& world_from_head, std::uint64_t stream);

}  // namespace purkinje::renderer
