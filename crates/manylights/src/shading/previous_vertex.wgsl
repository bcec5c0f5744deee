// Where a vertex was a frame before, in its draw's space: a deformed mesh's from its previous pose
// (`passes/deform.wgsl`), any other's where it is now. Group 1 binding 2 of the passes that include it.
@group(1) @binding(2) var<storage, read> previous_positions: array<vec4<f32>>;

fn previous_vertex_position(vertex_index: u32, position: vec3<f32>) -> vec4<f32> {
    if vertex_index < arrayLength(&previous_positions) && previous_positions[vertex_index].w != 0.0 {
        return vec4<f32>(previous_positions[vertex_index].xyz, 1.0);
    }
    return vec4<f32>(position, 1.0);
}
