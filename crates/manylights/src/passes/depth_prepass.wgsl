// The forward pipeline's depth prepass: depth only, so the shading pass runs its fragment shader once
// per pixel (EQUAL depth test). Opaque draws need no fragment stage; alpha-masked ones discard here.
#include "passes/surface_raster.wgsl"

@fragment
fn depth_prepass_masked(in: ForwardVertex) {
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    if !forward_alpha_covers(in, g) {
        discard;
    }
}
