// module planes: bounding-plane (parallax) correction of cube-map lookups (000 §4.4.1,
// Fig. 4.5–4.6). CPU twins: lustre_shade::integrator::{BoundingPlane::intersect,
// BoundingPlane::corrected_direction, corrected_direction}. Equations: the secondary ray
// p + s·ω meets the plane (q, m) at s = ((q − p)·m) / (ω·m), accepted when |ω·m| > 1e-12, s > 0
// is finite and p lies strictly on the centre's side of the plane; over several planes the
// nearest hit wins; the cube map, whose projection centre is the origin, is then read towards
// the hit, ω' = (p + s ω)/‖p + s ω‖, and along ω itself
// when no plane is hit (or the hit is the centre).
//
// Positions are relative to the projection centre. The planes live in the pass's buffers: a
// pass folds them with `nearer_plane` and finishes with `corrected_lookup`.

struct BoundingPlane {
    // A point on the plane.
    point: vec3<f32>,
    // The unit normal (BoundingPlane::new normalizes it on the CPU).
    normal: vec3<f32>,
}

// BoundingPlane::intersect: the ray parameter s > 0 where p + s·ω meets the plane, −1 for none
// (parallel, behind, not finite, or p not strictly on the projection centre's side: a point on
// the plane or beyond it is not bounded by it).
fn plane_distance(plane: BoundingPlane, p: vec3<f32>, w: vec3<f32>) -> f32 {
    let denom = dot(w, plane.normal);
    if (!(abs(denom) > 1e-12)) {
        return -1.0;
    }
    let gap = dot(plane.point - p, plane.normal);
    if (!(gap * dot(plane.point, plane.normal) > 0.0)) {
        return -1.0;
    }
    let s = gap / denom;
    if (!(s > 0.0 && s <= 3.4e38)) {
        return -1.0;
    }
    return s;
}

// One step of corrected_direction's search: the nearer of `best` (−1 for none yet) and this
// plane's hit; a later plane wins only when strictly nearer.
fn nearer_plane(best: f32, plane: BoundingPlane, p: vec3<f32>, w: vec3<f32>) -> f32 {
    let s = plane_distance(plane, p, w);
    if (s > 0.0 && (best < 0.0 || s < best)) {
        return s;
    }
    return best;
}

// The lookup direction for the nearest hit `s` (−1: none) of the ray p + s·ω: the unit vector
// towards the hit (glam's try_normalize: ω when the length is 0 or not finite), else ω.
fn corrected_lookup(s: f32, p: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    if (!(s > 0.0)) {
        return w;
    }
    let q = p + w * s;
    let inv = 1.0 / length(q);
    if (!(inv > 0.0 && inv <= 3.4e38)) {
        return w;
    }
    return q * inv;
}

// BoundingPlane::corrected_direction: the correction by a single plane.
fn plane_corrected_direction(plane: BoundingPlane, p: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    return corrected_lookup(plane_distance(plane, p, w), p, w);
}
