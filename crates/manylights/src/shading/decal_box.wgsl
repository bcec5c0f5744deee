// A conservative test of a decal's box against an axis-aligned box, for queries that test a decal
// once for all the points of a subgroup's lanes: leaves shared out among them
// (`shading/enumerate/decal_leaves_shared_out.wgsl`) and cell lists (`decals_bvh_cells.wgsl`).

// Whether the decal box with rows `decal_from_group` (`shading/decals.wgsl`) may overlap the box
// [lo, hi]: along each of the decal's axes, the box's centre lies within the decal's half-width plus the
// box's reach along that axis. The decal's three separating axes alone: a conservative test, since
// each lane's own test decides, with a margin for the rounding of both tests that grows with the
// coordinates' magnitude (small decals far from their group's origin).
fn decal_box_meets_box(decal_from_group: mat3x4<f32>, lo: vec3<f32>, hi: vec3<f32>) -> bool {
    let half = (hi - lo) * 0.5;
    let middle = (lo + hi) * 0.5;
    let span = abs(middle) + half;
    let x = decal_from_group[0];
    let y = decal_from_group[1];
    let z = decal_from_group[2];
    let centre = vec4<f32>(middle, 1.0) * decal_from_group;
    let reach = vec3<f32>(dot(abs(x.xyz), half), dot(abs(y.xyz), half), dot(abs(z.xyz), half));
    let magnitude = vec3<f32>(dot(abs(x.xyz), span) + abs(x.w), dot(abs(y.xyz), span) + abs(y.w), dot(abs(z.xyz), span) + abs(z.w));
    return all(abs(centre) <= vec3<f32>(0.5) + reach + 1e-6 * (magnitude + 1.0));
}
