// What a draw's record tells beyond its vertices: the draw a visibility id belongs to, and how much
// its transform scales lengths.
#include "shading/scene_bindings.wgsl"

// The draw whose visibility ids contain `id`: the last one starting at or before it.
fn find_draw(id: u32) -> u32 {
    var low = 0u;
    var high = arrayLength(&draws) - 1u;
    while low < high {
        let mid = (low + high + 1u) / 2u;
        if draws[mid].first_visibility_id <= id {
            low = mid;
        } else {
            high = mid - 1u;
        }
    }
    return low;
}

// How much a draw scales lengths on average: the cube root of its transform's volume change.
fn draw_scale(draw: Draw) -> f32 {
    let m = draw.world_from_local;
    return pow(abs(determinant(mat3x3<f32>(m[0].xyz, m[1].xyz, m[2].xyz))), 1.0 / 3.0);
}
