//! The CPU scene: meshes, materials, textures, instances, lights, cameras and global lighting.
//!
//! Everything here is plain data with no GPU types, so it can be built by the glTF importer, the TOML
//! scene file, the procedural demo or a test, then handed to `gpu::GpuScene` in one direction.
//!
//! Conventions: right-handed, +Y up, metres; a camera looks down its local -Z (as in glTF).

mod aabb;
pub mod animation;
pub mod camera;
pub mod decal_textures;
pub mod deform;
pub mod demo;
pub mod environment;
pub mod generators;
pub mod gltf;
pub mod ibl;
pub mod paper_scenes;
pub mod particles;
pub mod pose;
pub mod scene_file;
pub mod sky;
mod tangents;

use std::path::Path;

use glam::{Affine2, Affine3A, Mat4, Vec3, Vec4};

use crate::settings::SettingsOverlay;

pub use aabb::Aabb;
pub use camera::{Camera, Projection};
pub use environment::Environment;
pub use particles::ParticleSettings;

/// What the image decoder (the `image` crate's default limits) may allocate for one image, in MiB.
pub const IMAGE_DECODE_LIMIT_MIB: u64 = 512;

/// Illuminance (intensity / d²) at which a light without an explicit range is cut off: its range is
/// derived with [`Light::range_from_cutoff`] and this value.
pub const DEFAULT_LIGHT_CUTOFF: f32 = 0.01;

/// Loads a scene file, choosing the loader from the extension: `.gltf`/`.glb` (glTF 2.0) or `.toml`
/// (a [`scene_file`] that may reference a glTF and add lights), with what a scene file asks of the
/// renderer (`[rays]`, `[particles]`' rendering keys) as an overlay on the settings.
pub fn load(path: &Path) -> crate::Result<(Scene, SettingsOverlay)> {
    let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("gltf" | "glb") => Ok((self::gltf::import(path)?, SettingsOverlay::default())),
        Some("toml") => scene_file::load(path),
        _ => Err(crate::Error::InvalidConfig(format!("{}: unknown scene type; expected .gltf, .glb or .toml", path.display()))),
    }
}

/// [`load`]'s scene alone, for callers that render with settings of their own.
pub fn load_path(path: &Path) -> crate::Result<Scene> {
    load(path).map(|(scene, _)| scene)
}

/// One vertex, laid out exactly as the shaders read it (`shading/types.wgsl`, `Vertex`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub u: f32,
    pub normal: [f32; 3],
    pub v: f32,
    /// xyz: tangent, w: bitangent sign (glTF / MikkTSpace convention).
    pub tangent: [f32; 4],
    /// Linear RGBA as 16-bit unsigned normalized integers (glTF's `COLOR_0`), which multiplies the
    /// material's base colour and alpha: [`Vertex::WHITE`] where a mesh has none.
    pub color: [u16; 4],
    /// The second set of texture coordinates (glTF's `TEXCOORD_1`), read by the textures whose
    /// [`TextureRef::tex_coord`] is 1; zero where a mesh has none.
    pub uv1: [f32; 2],
}

impl Vertex {
    pub const WHITE: [u16; 4] = [u16::MAX; 4];

    /// `color`, components clamped to 0..1 (NaN taken as 1), as [`Vertex::color`] stores it.
    pub fn color_from(color: [f32; 4]) -> [u16; 4] {
        color.map(|c| if c.is_nan() { u16::MAX } else { (c.clamp(0.0, 1.0) * 65535.0).round() as u16 })
    }

    /// Texture coordinates `set`: 0 is `TEXCOORD_0` (u, v), 1 `TEXCOORD_1` (`uv1`).
    pub fn uv(&self, set: u32) -> [f32; 2] {
        if set == 1 {
            self.uv1
        } else {
            [self.u, self.v]
        }
    }
}

impl Default for Vertex {
    fn default() -> Self {
        Self { position: [0.0; 3], u: 0.0, normal: [0.0; 3], v: 0.0, tangent: [0.0; 4], color: Self::WHITE, uv1: [0.0; 2] }
    }
}

/// An indexed triangle list with one material.
#[derive(Clone, Debug)]
pub struct Primitive {
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
    pub material: usize,
}

impl Primitive {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

#[derive(Clone, Debug)]
pub struct Mesh {
    pub name: String,
    pub primitives: Vec<Primitive>,
}

/// A mesh placed in the world; the node hierarchy is flattened into `world_from_local`.
#[derive(Clone, Debug)]
pub struct Instance {
    pub mesh: usize,
    pub world_from_local: Mat4,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    Opaque,
    /// Discard where alpha < cutoff.
    Mask {
        cutoff: f32,
    },
    /// Blended over what lies behind it by its base colour's alpha, after the opaque surfaces are
    /// shaded, each pixel's layers sorted far to near (`passes/blended_shade.rs`).
    Blend,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Wrap {
    #[default]
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

/// A material's use of a texture: which image, how its coordinates wrap, which of the mesh's sets of
/// coordinates it reads and how they are transformed (glTF's `texCoord` and `KHR_texture_transform`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    pub texture: usize,
    pub wrap_u: Wrap,
    pub wrap_v: Wrap,
    /// 0: `TEXCOORD_0` (the vertices' u, v); 1: `TEXCOORD_1` ([`Vertex::uv1`]).
    pub tex_coord: u32,
    pub uv_transform: Affine2,
}

impl TextureRef {
    /// Image `texture` read at the mesh's first coordinates as they are.
    pub fn new(texture: usize, wrap_u: Wrap, wrap_v: Wrap) -> Self {
        Self { texture, wrap_u, wrap_v, tex_coord: 0, uv_transform: Affine2::IDENTITY }
    }
}

/// glTF metallic-roughness material.
#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    pub base_color_factor: Vec4,
    pub base_color_texture: Option<TextureRef>,
    pub metallic_factor: f32,
    pub roughness_factor: f32,
    /// glTF layout: G = roughness, B = metallic.
    pub metallic_roughness_texture: Option<TextureRef>,
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
    /// glTF's ambient occlusion: R = how much of the environment's light reaches the surface.
    pub occlusion_texture: Option<TextureRef>,
    /// How far the occlusion texture darkens: 1 + strength × (R − 1).
    pub occlusion_strength: f32,
    pub emissive_factor: Vec3,
    pub emissive_texture: Option<TextureRef>,
    pub alpha_mode: AlphaMode,
    pub double_sided: bool,
    /// `KHR_materials_unlit`: the base colour is the radiance sent, and nothing lights it.
    pub unlit: bool,
    /// The dielectric's reflectance (`KHR_materials_ior`, `KHR_materials_specular`).
    pub specular: Specular,
    /// A clear coat over the material (`KHR_materials_clearcoat`).
    pub clearcoat: Option<Clearcoat>,
    /// Light passing through the surface (`KHR_materials_transmission`, `KHR_materials_volume`).
    pub transmission: Option<Transmission>,
    /// A sheen layer over the material (`KHR_materials_sheen`): cloth's back-scattering fibres.
    pub sheen: Option<Sheen>,
}

/// A dielectric's specular reflection, as `KHR_materials_ior` and `KHR_materials_specular` define
/// it: at normal incidence `min(((ior − 1) / (ior + 1))² × colour, 1) × factor`, at grazing
/// incidence `factor`; the diffuse lobe keeps what the specular lobe does not reflect.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Specular {
    pub ior: f32,
    pub factor: f32,
    /// Its alpha channel scales `factor`.
    pub texture: Option<TextureRef>,
    pub color_factor: Vec3,
    /// sRGB colour scaling `color_factor`.
    pub color_texture: Option<TextureRef>,
}

impl Default for Specular {
    /// glTF's core material: an index of refraction of 1.5 (4 % reflectance), untinted.
    fn default() -> Self {
        Self { ior: 1.5, factor: 1.0, texture: None, color_factor: Vec3::ONE, color_texture: None }
    }
}

/// A clear coat (`KHR_materials_clearcoat`): a GGX layer of index of refraction 1.5 over the
/// material, of strength `factor` (× the texture's R) and roughness `roughness_factor` (× the
/// roughness texture's G), with a normal of its own (the normal texture's, else the geometry's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clearcoat {
    pub factor: f32,
    pub texture: Option<TextureRef>,
    pub roughness_factor: f32,
    pub roughness_texture: Option<TextureRef>,
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
}

/// Light passing through a dielectric (`KHR_materials_transmission`): a share `factor` (× the
/// texture's R) of what its diffuse lobe would scatter is instead let through, refracted by the
/// specular's index of refraction and blurred by its roughness. With `KHR_materials_volume`, the
/// surface bounds a medium `thickness_factor` deep (× the thickness texture's G, in the mesh's units;
/// 0: thin-walled) through which light of `attenuation_color` is left after `attenuation_distance`
/// (Beer's law; infinite: clear). With `KHR_materials_dispersion`, the medium's index of refraction
/// spreads over the colours by `dispersion` (20 / the Abbe number; 0: none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transmission {
    pub factor: f32,
    pub texture: Option<TextureRef>,
    pub thickness_factor: f32,
    pub thickness_texture: Option<TextureRef>,
    pub attenuation_distance: f32,
    pub attenuation_color: Vec3,
    pub dispersion: f32,
}

/// A sheen (`KHR_materials_sheen`): a layer of fibres over the material scattering back towards
/// grazing views, in `color_factor` (× the sRGB colour texture) with roughness `roughness_factor`
/// (× the roughness texture's A), through the Charlie distribution (Estevez & Kulla 2017); the
/// material below keeps what the layer does not reflect.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sheen {
    pub color_factor: Vec3,
    pub color_texture: Option<TextureRef>,
    pub roughness_factor: f32,
    pub roughness_texture: Option<TextureRef>,
}

impl Sheen {
    /// A sheen of `color` and `roughness` without textures.
    pub fn untextured(color: Vec3, roughness: f32) -> Self {
        Self { color_factor: color, color_texture: None, roughness_factor: roughness, roughness_texture: None }
    }
}

impl Transmission {
    /// A thin-walled surface letting `factor` through, without textures.
    pub fn thin(factor: f32) -> Self {
        Self {
            factor,
            texture: None,
            thickness_factor: 0.0,
            thickness_texture: None,
            attenuation_distance: f32::INFINITY,
            attenuation_color: Vec3::ONE,
            dispersion: 0.0,
        }
    }
}

impl Clearcoat {
    /// A coat of `factor` and `roughness` without textures.
    pub fn untextured(factor: f32, roughness: f32) -> Self {
        Self { factor, texture: None, roughness_factor: roughness, roughness_texture: None, normal_texture: None, normal_scale: 1.0 }
    }
}

impl Default for Material {
    /// The glTF default material.
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color_factor: Vec4::ONE,
            base_color_texture: None,
            metallic_factor: 1.0,
            roughness_factor: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            emissive_factor: Vec3::ZERO,
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            unlit: false,
            specular: Specular::default(),
            clearcoat: None,
            transmission: None,
            sheen: None,
        }
    }
}

impl Material {
    /// Drawn after the opaque surfaces, over the image of them: blended (glTF BLEND) or letting
    /// light through. Such surfaces hold no pixel of the opaque surfaces' G-buffer or visibility
    /// buffer and are left out of the ray structures: they cast no traced shadow and reflections see
    /// past them.
    pub fn drawn_over_opaque(&self) -> bool {
        self.alpha_mode == AlphaMode::Blend || self.transmission.is_some()
    }

    /// Transmissive without blending: drawn over the opaque image as a surface that hides what
    /// lies behind it, so that at each pixel only the nearest is shaded.
    pub fn transmissive_unblended(&self) -> bool {
        self.alpha_mode != AlphaMode::Blend && self.transmission.is_some()
    }

    /// Every texture the material uses, with whether it holds sRGB colour (else linear data).
    pub fn textures(&self) -> impl Iterator<Item = (TextureRef, bool)> + '_ {
        let clearcoat = self.clearcoat.iter().flat_map(|c| [c.texture, c.roughness_texture, c.normal_texture]);
        let transmission = self.transmission.iter().flat_map(|t| [t.texture, t.thickness_texture]);
        let sheen_color = self.sheen.map(|s| s.color_texture);
        [(self.base_color_texture, true), (self.emissive_texture, true), (self.specular.color_texture, true)]
            .into_iter()
            .chain(sheen_color.map(|t| (t, true)))
            .chain(
                [self.metallic_roughness_texture, self.normal_texture, self.specular.texture, self.occlusion_texture]
                    .into_iter()
                    .map(|t| (t, false)),
            )
            .chain(clearcoat.chain(transmission).chain(self.sheen.map(|s| s.roughness_texture)).map(|t| (t, false)))
            .filter_map(|(t, srgb)| t.map(|t| (t, srgb)))
    }
}

/// A decoded image, RGBA8. Whether it holds sRGB colour or linear data follows from how materials use
/// it; the GPU scene uploads it accordingly.
#[derive(Clone, Debug)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub rgba8: Vec<u8>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    Point,
    /// Cone angles in radians from the axis, 0 ≤ inner < outer ≤ π/2 (KHR_lights_punctual).
    Spot {
        inner_cone_angle: f32,
        outer_cone_angle: f32,
    },
}

/// A punctual light (KHR_lights_punctual units: candela), with a finite range of influence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub kind: LightKind,
    pub position: Vec3,
    /// Unit direction the light points along (spot lights).
    pub direction: Vec3,
    pub color: Vec3,
    pub intensity: f32,
    /// Distance where the glTF window function reaches zero.
    pub range: f32,
    /// Whether shading traces a shadow ray towards it (within the frame's per-point budget,
    /// `settings::RaySettings::light_shadow_rays`).
    pub cast_shadows: bool,
}

impl Light {
    /// Range where intensity / d² falls to `cutoff`: for lights that come without an explicit range.
    pub fn range_from_cutoff(intensity: f32, color: Vec3, cutoff: f32) -> f32 {
        (intensity * color.max_element() / cutoff).sqrt()
    }
}

/// Directional light, illuminance in lux (scene-relative units in the demo).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Unit direction the light travels (from the sun towards the scene).
    pub direction: Vec3,
    pub color: Vec3,
    pub illuminance: f32,
}

/// Number of decal layers: layers are blended bottom (0) to top, decals within a layer
/// order-independently (weighted blended OIT, `shading/decals.wgsl`).
pub const DECAL_LAYERS: u32 = 4;

/// A decal: a material projected onto every surface inside an oriented box.
///
/// Decal space is the unit box [-0.5, 0.5]³. The decal projects along its local -Z onto surfaces whose
/// normal faces +Z (it fades out on surfaces seen edge-on from the projector and is absent on surfaces
/// facing away); the image's u runs along +X and v along -Y, like a picture looked at from +Z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decal {
    /// Maps decal space into the decal's group space (world space when the decals are not grouped).
    pub world_from_decal: Affine3A,
    /// The material whose base colour (albedo and alpha), metallic-roughness and normal texture it
    /// projects. Factors apply as on surfaces; without a normal texture the decal leaves normals alone.
    /// Its textures are sampled clamped to their edges, whatever their wrap modes: a decal projects
    /// its image once over its box.
    pub material: usize,
    /// 0 .. DECAL_LAYERS - 1; higher layers cover lower ones.
    pub layer: u32,
    /// Weight in its layer's weighted blend, > 0.
    pub weight: f32,
}

/// A rigid motion over time: rotation about the vertical axis through `pivot`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spin {
    pub pivot: Vec3,
    pub radians_per_second: f32,
}

/// One placement of a group of lights or decals: the top level of their acceleration structure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroupInstance {
    pub group: usize,
    /// Maps the group's space into the world: a rotation, a translation and a uniform scale (ranges
    /// scale with it), so volumes keep their shape.
    pub world_from_group: Affine3A,
    /// Moves the instance rigidly over time; `None` keeps it still.
    pub spin: Option<Spin>,
}

impl GroupInstance {
    /// The instance's transform at `time` seconds.
    pub fn world_from_group_at(&self, time: f32) -> Affine3A {
        match self.spin {
            Some(spin) => {
                let rotation = Affine3A::from_rotation_y(spin.radians_per_second * time);
                Affine3A::from_translation(spin.pivot) * rotation * Affine3A::from_translation(-spin.pivot) * self.world_from_group
            }
            None => self.world_from_group,
        }
    }
}

/// How lights or decals are grouped and placed. Items are stored group after group, each group's in
/// its own space; instances place groups in the world, a group any number of times. The default,
/// no groups, means one group of all items placed once where they are.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Groups {
    /// Item count of each group, in storage order; they add up to the number of items.
    pub sizes: Vec<usize>,
    pub instances: Vec<GroupInstance>,
}

impl Groups {
    /// The item range of each group and the instances, with the default applied for `item_count` items.
    pub fn resolve(&self, item_count: usize) -> (Vec<std::ops::Range<usize>>, Vec<GroupInstance>) {
        if self.sizes.is_empty() {
            let identity = GroupInstance { group: 0, world_from_group: Affine3A::IDENTITY, spin: None };
            let all = 0..item_count;
            return (vec![all], vec![identity]);
        }
        let mut start = 0;
        let ranges = self
            .sizes
            .iter()
            .map(|&n| {
                start += n;
                start - n..start
            })
            .collect();
        (ranges, self.instances.clone())
    }

    /// The items as placed, for `item_count` items: each group's once per instance of it.
    pub fn placed_count(&self, item_count: usize) -> usize {
        let (ranges, instances) = self.resolve(item_count);
        instances.iter().map(|i| ranges[i.group].len()).sum()
    }

    /// Whether any instance moves over time.
    pub fn is_animated(&self) -> bool {
        self.instances.iter().any(|i| i.spin.is_some())
    }

    /// Checks the grouping of `item_count` items; the message names the bad group or instance.
    pub fn validate(&self, item_count: usize) -> Result<(), String> {
        if self.sizes.is_empty() {
            return if self.instances.is_empty() { Ok(()) } else { Err("instances are given but no groups".into()) };
        }
        let total: usize = self.sizes.iter().sum();
        if total != item_count {
            return Err(format!("the groups hold {total} items but there are {item_count}"));
        }
        for (i, instance) in self.instances.iter().enumerate() {
            if instance.group >= self.sizes.len() {
                return Err(format!("instance {i}: group {} does not exist ({} groups)", instance.group, self.sizes.len()));
            }
            validate_similarity(&instance.world_from_group).map_err(|m| format!("instance {i}: {m}"))?;
            if let Some(spin) = instance.spin {
                if !(spin.pivot.is_finite() && spin.radians_per_second.is_finite()) {
                    return Err(format!("instance {i}: spin pivot and speed must be finite"));
                }
            }
        }
        Ok(())
    }
}

/// Checks that a transform is a rotation, translation and uniform scale, as group instances must be.
fn validate_similarity(t: &Affine3A) -> Result<(), String> {
    if !t.is_finite() {
        return Err("transform is NaN or infinite".into());
    }
    let m = t.matrix3;
    let scale = m.x_axis.length();
    let unit = |v: glam::Vec3A| (v.length() - scale).abs() <= 1e-4 * scale;
    let orthogonal = m.x_axis.dot(m.y_axis).abs() <= 1e-4 * scale * scale
        && m.x_axis.dot(m.z_axis).abs() <= 1e-4 * scale * scale
        && m.y_axis.dot(m.z_axis).abs() <= 1e-4 * scale * scale;
    if !(scale > 0.0 && unit(m.y_axis) && unit(m.z_axis) && orthogonal && m.determinant() > 0.0) {
        return Err("transform must be a rotation, translation and positive uniform scale".into());
    }
    Ok(())
}

/// Checks one decal; the message says which field is wrong.
pub fn validate_decal(d: &Decal, material_count: usize) -> Result<(), String> {
    if !d.world_from_decal.is_finite() {
        return Err("transform is NaN or infinite".into());
    }
    let det = d.world_from_decal.matrix3.determinant();
    if !(det.is_finite() && det.abs() > f32::MIN_POSITIVE) {
        return Err("transform is degenerate: the box has no volume".into());
    }
    if d.material >= material_count {
        return Err(format!("material {} does not exist", d.material));
    }
    if d.layer >= DECAL_LAYERS {
        return Err(format!("layer {} is not below {DECAL_LAYERS}", d.layer));
    }
    if !(d.weight.is_finite() && d.weight > 0.0) {
        return Err(format!("weight {} must be finite and > 0", d.weight));
    }
    Ok(())
}

#[derive(Clone, Debug)]
pub struct Scene {
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub instances: Vec<Instance>,
    /// Lights, in their group's space (`light_groups`).
    pub lights: Vec<Light>,
    /// How many of `lights`, from the first, are the scene's own (glTF and scene-file lights); the
    /// generators' follow. Only the scene's own lights keep `settings::Sky::Auto` from the sky.
    pub authored_lights: usize,
    pub light_groups: Groups,
    /// Decals, in their group's space (`decal_groups`).
    pub decals: Vec<Decal>,
    pub decal_groups: Groups,
    pub cameras: Vec<Camera>,
    pub sun: Option<Sun>,
    /// Uniform ambient radiance, a stand-in for indirect light where there is no `environment`.
    pub ambient: Vec3,
    /// Radiance from afar (the daylight sky, `sky::light_with_sky`, or an HDR image): the background
    /// and image-based lighting. `None`: a uniform environment of `ambient`.
    pub environment: Option<Environment>,
    /// Moving particle lights (`particles/`), if any.
    pub particles: Option<ParticleSettings>,
    /// Node animation moving mesh instances and skin joints (glTF animations), if any; a scene with
    /// a skin has one, its channels perhaps empty.
    pub animation: Option<animation::Animation>,
    /// Meshes deformed every frame (`deform`), at most one deformer per mesh.
    pub deformers: Vec<deform::Deformer>,
    /// The files the scene was read from (canonical paths), which no output may overwrite.
    pub source_files: Vec<std::path::PathBuf>,
}

impl Default for Scene {
    fn default() -> Self {
        Self {
            meshes: Vec::new(),
            materials: Vec::new(),
            textures: Vec::new(),
            instances: Vec::new(),
            lights: Vec::new(),
            authored_lights: 0,
            light_groups: Groups::default(),
            decals: Vec::new(),
            decal_groups: Groups::default(),
            cameras: Vec::new(),
            sun: None,
            ambient: Vec3::splat(0.03),
            environment: None,
            particles: None,
            animation: None,
            deformers: Vec::new(),
            source_files: Vec::new(),
        }
    }
}

impl Scene {
    /// Whether anything in it changes over time: particles, animated instances, moving light or
    /// decal groups, deformed meshes.
    pub fn changes_over_time(&self) -> bool {
        self.particles.as_ref().is_some_and(|p| p.count > 0)
            || self.animation.as_ref().is_some_and(|a| !a.instances.is_empty())
            || self.light_groups.is_animated()
            || self.decal_groups.is_animated()
            || !self.deformers.is_empty()
    }

    /// Triangles as drawn: each mesh counted once per instance.
    pub fn drawn_triangle_count(&self) -> usize {
        self.instances.iter().map(|i| self.meshes[i.mesh].primitives.iter().map(Primitive::triangle_count).sum::<usize>()).sum()
    }

    /// World-space bounds of all instances.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for inst in &self.instances {
            for prim in &self.meshes[inst.mesh].primitives {
                for v in &prim.vertices {
                    b.grow_point(inst.world_from_local.transform_point3(Vec3::from(v.position)));
                }
            }
        }
        b
    }

    /// Checks the invariants every consumer relies on: indices in range, finite numbers, valid
    /// references. Importers and generators call it so bad data fails early with a clear message.
    pub fn validate(&self) -> crate::Result<()> {
        if let Some(particles) = &self.particles {
            particles.validate()?;
        }
        let err = |m: String| Err(crate::Error::InvalidScene(m));
        for (mi, mesh) in self.meshes.iter().enumerate() {
            for (pi, p) in mesh.primitives.iter().enumerate() {
                if p.indices.len() % 3 != 0 {
                    return err(format!("mesh {mi} primitive {pi}: index count {} is not a multiple of 3", p.indices.len()));
                }
                if let Some(&bad) = p.indices.iter().find(|&&i| i as usize >= p.vertices.len()) {
                    return err(format!("mesh {mi} primitive {pi}: index {bad} out of range ({} vertices)", p.vertices.len()));
                }
                if p.material >= self.materials.len() {
                    return err(format!("mesh {mi} primitive {pi}: material {} does not exist", p.material));
                }
                if p.vertices.iter().any(|v| !v.position.iter().all(|c| c.is_finite())) {
                    return err(format!("mesh {mi} primitive {pi}: a vertex position is NaN or infinite"));
                }
            }
        }
        for (ii, inst) in self.instances.iter().enumerate() {
            if inst.mesh >= self.meshes.len() {
                return err(format!("instance {ii}: mesh {} does not exist", inst.mesh));
            }
            if !inst.world_from_local.is_finite() {
                return err(format!("instance {ii}: transform is NaN or infinite"));
            }
        }
        if let Some(animation) = &self.animation {
            animation.validate(self.instances.len()).map_err(crate::Error::InvalidScene)?;
        }
        for (ci, camera) in self.cameras.iter().enumerate() {
            let named = if camera.name == format!("camera {ci}") { String::new() } else { format!(" ({})", camera.name) };
            camera.projection.validate().map_err(|m| crate::Error::InvalidScene(format!("camera {ci}{named}: {m}")))?;
        }
        for (i, d) in self.deformers.iter().enumerate() {
            if d.mesh >= self.meshes.len() {
                return err(format!("deformer {i}: mesh {} does not exist", d.mesh));
            }
            if self.deformers[..i].iter().any(|other| other.mesh == d.mesh) {
                return err(format!("deformer {i}: mesh {} ({}) has a deformer already", d.mesh, self.meshes[d.mesh].name));
            }
            let checked = match &d.deformation {
                deform::Deformation::Wave(wave) => wave.validate(),
                deform::Deformation::Pose(pose) => {
                    let vertices = self.meshes[d.mesh].primitives.iter().map(|p| p.vertices.len()).sum();
                    let nodes = self.animation.as_ref().map_or(0, |a| a.nodes.len());
                    pose.validate(vertices, nodes)
                }
            };
            checked.map_err(|m| crate::Error::InvalidScene(format!("deformer {i} ({}): {m}", self.meshes[d.mesh].name)))?;
        }
        for (mi, m) in self.materials.iter().enumerate() {
            let named = if m.name == format!("material {mi}") { m.name.clone() } else { format!("material {mi} ({})", m.name) };
            validate_material(m).map_err(|reason| crate::Error::InvalidScene(format!("{named}: {reason}")))?;
            for (t, _) in m.textures() {
                if t.texture >= self.textures.len() {
                    return err(format!("material {mi} ({}): texture {} does not exist", m.name, t.texture));
                }
                if t.tex_coord > 1 {
                    return err(format!(
                        "material {mi} ({}): a texture reads TEXCOORD_{}; give 0 (TEXCOORD_0) or 1 (TEXCOORD_1)",
                        m.name, t.tex_coord
                    ));
                }
            }
        }
        for (li, l) in self.lights.iter().enumerate() {
            validate_light(l).map_err(|m| crate::Error::InvalidScene(format!("light {li}: {m}")))?;
        }
        self.light_groups.validate(self.lights.len()).map_err(|m| crate::Error::InvalidScene(format!("light groups: {m}")))?;
        for (di, d) in self.decals.iter().enumerate() {
            validate_decal(d, self.materials.len()).map_err(|m| crate::Error::InvalidScene(format!("decal {di}: {m}")))?;
        }
        self.decal_groups.validate(self.decals.len()).map_err(|m| crate::Error::InvalidScene(format!("decal groups: {m}")))?;
        if let Some(sun) = &self.sun {
            if !(sun.direction.is_finite()
                && sun.direction.length() > 0.0
                && sun.color.is_finite()
                && sun.illuminance.is_finite()
                && sun.illuminance >= 0.0)
            {
                return err("sun: direction, colour and illuminance must be finite, illuminance ≥ 0 and the direction non-zero".into());
            }
        }
        if !(self.ambient.is_finite() && self.ambient.min_element() >= 0.0) {
            return err("ambient must be finite and ≥ 0".into());
        }
        if let Some(e) = &self.environment {
            if e.width == 0 || e.height == 0 || e.radiance.len() != (e.width as usize) * (e.height as usize) {
                return err(format!("environment: {} radiance values for {}×{} texels", e.radiance.len(), e.width, e.height));
            }
            if !e.radiance.iter().flatten().all(|c| c.is_finite() && *c >= 0.0) {
                return err("environment: radiance must be finite and ≥ 0".into());
            }
        }
        Ok(())
    }
}

/// Checks a material's factors: colours and fractions within 0 to 1, emission finite and ≥ 0 (as
/// bright as it likes), scales finite. The message names the field and its allowed range.
pub fn validate_material(m: &Material) -> Result<(), String> {
    let unit = |x: f32| (0.0..=1.0).contains(&x);
    if !m.base_color_factor.to_array().into_iter().all(unit) {
        return Err(format!("base colour factor {:?} must be 0 to 1 in each component", m.base_color_factor.to_array()));
    }
    if !unit(m.metallic_factor) || !unit(m.roughness_factor) {
        return Err(format!("metallic factor {} and roughness factor {} must be 0 to 1", m.metallic_factor, m.roughness_factor));
    }
    if !(m.emissive_factor.is_finite() && m.emissive_factor.min_element() >= 0.0) {
        return Err(format!("emission {:?} must be finite and ≥ 0 in each component", m.emissive_factor.to_array()));
    }
    if !m.normal_scale.is_finite() {
        return Err(format!("normal scale {} must be finite", m.normal_scale));
    }
    let specular = &m.specular;
    // glTF allows an index of refraction of 0 (a perfect reflector) or at least 1.
    if !(specular.ior.is_finite() && (specular.ior == 0.0 || specular.ior >= 1.0)) {
        return Err(format!("index of refraction {} must be 0 or at least 1", specular.ior));
    }
    if !(unit(specular.factor) && specular.color_factor.is_finite() && specular.color_factor.min_element() >= 0.0) {
        return Err(format!(
            "specular factor {} must be 0 to 1 and specular colour {:?} finite and ≥ 0",
            specular.factor,
            specular.color_factor.to_array()
        ));
    }
    if let Some(c) = &m.clearcoat {
        if !unit(c.factor) || !unit(c.roughness_factor) || !c.normal_scale.is_finite() {
            return Err(format!(
                "clearcoat factor {} and roughness {} must be 0 to 1, its normal scale {} finite",
                c.factor, c.roughness_factor, c.normal_scale
            ));
        }
    }
    if let Some(t) = &m.transmission {
        if !(unit(t.factor) && t.thickness_factor.is_finite() && t.thickness_factor >= 0.0) {
            return Err(format!("transmission factor {} must be 0 to 1 and thickness {} finite and ≥ 0", t.factor, t.thickness_factor));
        }
        if !(t.dispersion.is_finite() && t.dispersion >= 0.0) {
            return Err(format!("dispersion {} must be finite and ≥ 0", t.dispersion));
        }
        if !(t.attenuation_distance > 0.0 && t.attenuation_color.to_array().into_iter().all(unit)) {
            return Err(format!(
                "attenuation distance {} must be > 0 (infinite: none) and attenuation colour {:?} 0 to 1 in each component",
                t.attenuation_distance,
                t.attenuation_color.to_array()
            ));
        }
    }
    if let Some(sheen) = &m.sheen {
        if !(sheen.color_factor.to_array().into_iter().all(unit) && unit(sheen.roughness_factor)) {
            return Err(format!(
                "sheen colour {:?} and roughness {} must be 0 to 1 in each component",
                sheen.color_factor.to_array(),
                sheen.roughness_factor
            ));
        }
    }
    if let AlphaMode::Mask { cutoff } = m.alpha_mode {
        if !(cutoff.is_finite() && cutoff >= 0.0) {
            return Err(format!("alpha cutoff {cutoff} must be finite and ≥ 0"));
        }
    }
    Ok(())
}

/// Checks one light; the message says which field is wrong.
pub fn validate_light(l: &Light) -> Result<(), String> {
    if !l.position.is_finite() {
        return Err(format!("position {:?} is NaN or infinite", l.position.to_array()));
    }
    if !(l.color.is_finite() && l.color.min_element() >= 0.0) {
        return Err(format!("colour {:?} must be finite and ≥ 0", l.color.to_array()));
    }
    if !(l.intensity.is_finite() && l.intensity >= 0.0) {
        return Err(format!("intensity {} must be finite and ≥ 0", l.intensity));
    }
    if !(l.range.is_finite() && l.range > 0.0) {
        return Err(format!("range {} must be finite and > 0", l.range));
    }
    if let LightKind::Spot { inner_cone_angle, outer_cone_angle } = l.kind {
        if !(l.direction.is_finite() && (l.direction.length() - 1.0).abs() < 1e-3) {
            return Err(format!("spot direction {:?} must be a finite unit vector", l.direction.to_array()));
        }
        if !(inner_cone_angle >= 0.0 && inner_cone_angle < outer_cone_angle && outer_cone_angle <= std::f32::consts::FRAC_PI_2) {
            return Err(format!(
                "spot cone angles must satisfy 0 ≤ inner < outer ≤ π/2, got inner {inner_cone_angle}, outer {outer_cone_angle}"
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod test_support {
    use std::path::{Path, PathBuf};

    /// The shared test scenes (see `shared/assets/README.md`).
    pub fn assets_dir() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets")
    }

    /// A directory for one test's files, removed when dropped.
    pub struct TempDir(PathBuf);

    impl std::ops::Deref for TempDir {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            // Best effort: a leftover directory in the system temp dir is harmless.
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    /// A fresh, empty directory named after the test (and process, so parallel runs do not collide).
    pub fn temp_dir(test: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("manylights-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create a temporary directory");
        TempDir(dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn load_path_dispatches_on_extension() {
        let err = load_path(Path::new("scene.obj")).unwrap_err();
        assert!(err.to_string().contains("expected .gltf, .glb or .toml"), "{err}");
        // The extension is matched case-insensitively: a missing .GLB is the glTF loader's I/O error.
        let dir = test_support::temp_dir("load_path");
        let missing = load_path(&dir.join("missing.GLB"));
        assert!(matches!(missing, Err(crate::Error::Io { .. })), "{missing:?}");
        let scene = load_path(&test_support::assets_dir().join("box/Box.glb")).unwrap();
        assert_eq!(scene.drawn_triangle_count(), 12);
    }

    #[test]
    fn particles_and_spinning_groups_change_a_scene_over_time() {
        assert!(!Scene::default().changes_over_time());
        let particles = |count| Scene { particles: Some(ParticleSettings { count, ..Default::default() }), ..Default::default() };
        assert!(particles(10).changes_over_time());
        assert!(!particles(0).changes_over_time());
        let spin = Some(Spin { pivot: Vec3::ZERO, radians_per_second: 1.0 });
        let groups = Groups { sizes: vec![1], instances: vec![GroupInstance { group: 0, world_from_group: Affine3A::IDENTITY, spin }] };
        assert!(Scene { decal_groups: groups.clone(), ..Default::default() }.changes_over_time());
        assert!(Scene { light_groups: groups, ..Default::default() }.changes_over_time());
    }
}
