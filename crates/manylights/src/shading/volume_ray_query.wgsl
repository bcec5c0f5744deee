// The point query of the hardware back end (`accel/hardware.rs`): a ray of minimal length from the
// point, whose box candidates are the volumes whose box holds it (and, rarely, boxes within the ray's
// length, which the exact test rejects). The top levels hold only boxes, and every box is opaque:
// candidates are tested by the enumeration and never committed.

// No instance entered yet: instance custom indices have 24 bits.
const VOLUME_RAY_NO_INSTANCE: u32 = 0xffffffffu;

fn volume_ray_at(p: vec3<f32>) -> RayDesc {
    // A positive length: a segment of zero length may meet no box on some implementations.
    return RayDesc(RAY_FLAG_NONE, 0xffu, 0.0, 1e-6, p, vec3<f32>(0.0, 0.0, 1.0));
}
