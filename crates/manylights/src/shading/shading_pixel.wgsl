// The pixel whose opaque surface the shading core is lighting, for what is kept per pixel from frame
// to frame (`restir`'s reservoirs, `shading/direct/restir.wgsl`); NO_PIXEL at ray hits and on
// transparent surfaces, which keep nothing. Set by `shade_pixel` (`shading/shade.wgsl`).
const NO_PIXEL: u32 = 0xffffffffu;

var<private> shading_pixel: vec2<u32> = vec2<u32>(NO_PIXEL);
