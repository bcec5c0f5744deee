// The deferred pipeline's geometry pass: each visible fragment's surface and material (before decals)
// into the G-buffer (`passes/gbuffer.wgsl`). Materials are evaluated here, in the fragment stage, with
// its derivatives; lighting and decals happen in `deferred_shade`, in compute.
#include "passes/surface_raster.wgsl"
#include "passes/gbuffer.wgsl"

struct GBufferTexel {
    @location(0) albedo: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) roughness_metallic: vec4<f32>,
    @location(3) material: vec4<u32>,
}

fn gbuffer_texel(s: ShadingInput) -> GBufferTexel {
    var out: GBufferTexel;
    out.albedo = vec4<f32>(s.base_color, s.occlusion);
    out.normal = gbuffer_encode_normal(s.normal);
    out.roughness_metallic = vec4<f32>(s.roughness, s.metallic, 0.0, 0.0);
    out.material = gbuffer_encode_material(s);
    return out;
}

@fragment
fn gbuffer_opaque(in: ForwardVertex, @builtin(front_facing) front_facing: bool) -> GBufferTexel {
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    return gbuffer_texel(fragment_surface(in, front_facing, g));
}

@fragment
fn gbuffer_masked(in: ForwardVertex, @builtin(front_facing) front_facing: bool) -> GBufferTexel {
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    if !forward_alpha_covers(in, g) {
        discard;
    }
    return gbuffer_texel(fragment_surface(in, front_facing, g));
}
