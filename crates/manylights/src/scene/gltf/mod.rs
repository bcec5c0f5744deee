//! glTF 2.0 import (`.gltf` with external or embedded buffers, `.glb`) into a [`Scene`].
//!
//! The default scene's node hierarchy is flattened into instances; a mesh used by several nodes stays
//! one [`Mesh`]. Triangle strips and fans become lists, missing normals become flat normals, missing
//! tangents come from MikkTSpace, and every image is decoded to RGBA8 (in parallel: decoding dominates
//! load time). Cameras and `KHR_lights_punctual` lights on nodes are placed with their node's world
//! transform. The first animation's node channels (translation, rotation, scale) become the scene's
//! [`animation::Animation`] of the instances and skin joints they move; skins and morph targets, with
//! the animation's morph weights, become deformers posing their mesh (`scene::pose`). Vertex
//! attributes may be quantized (`KHR_mesh_quantization`).

mod compression;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use ::gltf::accessor::util::{Item, Iter as AccessorIter};
use ::gltf::accessor::{Accessor, DataType, Dimensions};
use ::gltf::animation::util::ReadOutputs;
use ::gltf::buffer;
use ::gltf::khr_lights_punctual::Kind;
use ::gltf::mesh::{Mode, Semantic};
use ::gltf::{Document, Node};
use glam::{Affine2, Mat2, Mat4, Quat, Vec2, Vec3, Vec4};

use super::deform::{Deformation, Deformer};
use super::{
    animation, pose, tangents, AlphaMode, Camera, Instance, Light, LightKind, Material, Mesh, Primitive, Projection, Scene, Sun, Texture,
    TextureRef, Vertex, Wrap, DEFAULT_LIGHT_CUTOFF,
};
use crate::files::{self, guard, InputKind, LoadBudget};
use crate::{Error, Result};

/// Extensions a file may require; every other optional extension is ignored.
const SUPPORTED_EXTENSIONS: [&str; 20] = [
    INSTANCING,
    compression::MESHOPT,
    "EXT_texture_webp",
    "KHR_lights_punctual",
    "KHR_materials_clearcoat",
    "KHR_materials_dispersion",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    SPECULAR_GLOSSINESS,
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_materials_volume",
    compression::DRACO,
    "KHR_mesh_quantization",
    "KHR_texture_basisu",
    "KHR_texture_transform",
    // Variants choose other materials; with none chosen the default ones render, as the
    // specification has it.
    "KHR_materials_variants",
    // Metadata: nothing to render.
    "KHR_xmp_json_ld",
];

const INSTANCING: &str = "EXT_mesh_gpu_instancing";
/// The archived specular-glossiness workflow, read as metallic-roughness with `KHR_materials_specular`
/// (`specular_glossiness`).
const SPECULAR_GLOSSINESS: &str = "KHR_materials_pbrSpecularGlossiness";

/// Loads a glTF 2.0 file and everything it references (buffers and images next to it).
pub fn import(path: &Path) -> Result<Scene> {
    let budget = LoadBudget::new();
    let mut scene = import_within(path, &budget)?;
    scene.source_files = budget.files();
    Ok(scene)
}

/// [`import`] within a load's budget, which also records the files read.
pub(crate) fn import_within(path: &Path, budget: &LoadBudget) -> Result<Scene> {
    let kind = if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb")) { InputKind::Glb } else { InputKind::GltfJson };
    let bytes = files::read_input(path, kind, None, budget)?;
    guard::contain_panics(|| import_bytes(path, bytes, budget))
        .unwrap_or_else(|message| Err(Error::ParserPanic { path: path.to_owned(), parser: "glTF reader", message }))
}

fn import_bytes(path: &Path, bytes: Vec<u8>, budget: &LoadBudget) -> Result<Scene> {
    let invalid = |reason: String| gltf_error(path, reason);
    if bytes.is_empty() {
        return Err(invalid("the file is empty".into()));
    }
    // The parser reads anything without the GLB magic as JSON, and would report a JSON syntax error.
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb")) && !bytes.starts_with(b"glTF") {
        return Err(invalid("a .glb file starts with the bytes `glTF`, and this one does not: it is corrupt or not a GLB file".into()));
    }
    // A GLB's JSON chunk (its length after the 12-byte header) is held to what a .gltf may hold.
    if let Some(json_length) = bytes.get(12..16).filter(|_| bytes.starts_with(b"glTF")) {
        let json_length = u64::from(u32::from_le_bytes([json_length[0], json_length[1], json_length[2], json_length[3]]));
        if json_length > InputKind::GltfJson.cap() {
            return Err(invalid(format!(
                "its JSON chunk declares {}, over the {} manylights parses; give a smaller scene",
                files::read::human_bytes(json_length),
                files::read::human_bytes(InputKind::GltfJson.cap())
            )));
        }
    }
    // Parsed without validation first: the gltf crate reports an unsupported required extension as
    // a generic validation failure, and this check names it.
    let ::gltf::Gltf { document, blob } = parse(&bytes).map_err(|e| invalid(parse_reason(e)))?;
    drop(bytes);
    check_extensions(path, &document)?;
    let version = &document.as_json().asset.version;
    if version.split('.').next() != Some("2") {
        return Err(invalid(format!("asset.version is \"{version}\": only glTF 2.x files can be read")));
    }
    check_before_validation(document.as_json()).map_err(&invalid)?;
    // Buffers are read, and compressed geometry decoded into them, before validation: the gltf crate
    // refuses a Draco primitive's accessors, which have no buffer view until it is decoded.
    let base = path.parent().unwrap_or(Path::new("."));
    let mut root = document.into_json();
    let mut buffers = load_buffers(path, &root, base, blob, budget)?;
    compression::decode(&mut root, &mut buffers, budget, path).map_err(&invalid)?;
    // The gltf crate refuses required extensions it does not know; these were checked against ours.
    root.extensions_required.clear();
    let document = Document::from_json(root).map_err(|e| invalid(validation_reason(e)))?;

    check_sources(&document).map_err(&invalid)?;
    check_geometry_size(&document).map_err(&invalid)?;
    check_views(&document, &buffers).map_err(&invalid)?;
    let textures = decode_images(path, &document, base, &buffers, budget)?;
    let scene = build_scene(&document, &buffers, textures).map_err(&invalid)?;
    // The scene's own checks (cameras, indices, …), named by the file they came from.
    scene.validate().map_err(|e| match e {
        Error::InvalidScene(reason) => invalid(reason),
        e => e,
    })?;
    Ok(scene)
}

/// Checks, before anything is read, what the meshes and animations expand to: accessors may name
/// billions of elements (a sparse one without a buffer view costs no bytes in the file), and strips,
/// fans, flat shading, morph targets, skins, GPU instances and the copies of posed meshes multiply
/// them.
fn check_geometry_size(document: &Document) -> Result<(), String> {
    let vertex = std::mem::size_of::<Vertex>() as u64;
    let mut bytes = 0u64;
    // Each mesh's bytes, and whether nodes pose it (a copy per node).
    let mut mesh_bytes = Vec::with_capacity(document.meshes().len());
    let mut morphed = Vec::with_capacity(document.meshes().len());
    for mesh in document.meshes() {
        let mut this = 0u64;
        let mut targets = false;
        for p in mesh.primitives() {
            let vertices = p.get(&Semantic::Positions).map_or(0, |a| a.count() as u64);
            let indices = p.indices().map_or(vertices, |a| a.count() as u64);
            let triangle_corners = if matches!(p.mode(), Mode::TriangleStrip | Mode::TriangleFan) { indices * 3 } else { indices };
            // Read attributes (up to 5 of 16 bytes), the vertices, the index list, and flat shading's
            // vertex per corner; each morph target's three offsets read and kept, each skin set's
            // joints and weights.
            let attributes = vertices * (5 * 16 + vertex);
            let flat = if p.get(&Semantic::Normals).is_none() { triangle_corners * vertex } else { 0 };
            let morph = (p.morph_targets().len() as u64).saturating_mul(vertices * 96);
            let sets = (0..).take_while(|&s| p.get(&Semantic::Joints(s)).is_some()).count() as u64;
            targets |= p.morph_targets().len() > 0;
            this = this.saturating_add(attributes).saturating_add(triangle_corners * 8).saturating_add(flat);
            this = this.saturating_add(morph).saturating_add(sets.saturating_mul(vertices * 64));
        }
        bytes = bytes.saturating_add(this);
        mesh_bytes.push(this);
        morphed.push(targets);
    }
    for node in document.nodes() {
        let instances = node.extension_value(INSTANCING).and_then(|e| e.get("attributes")?.as_object().cloned()).map_or(1, |attributes| {
            attributes.values().filter_map(|i| document.accessors().nth(i.as_u64()? as usize)).map(|a| a.count() as u64).max().unwrap_or(1)
        });
        let posed = node.mesh().is_some_and(|m| morphed[m.index()] || node.skin().is_some());
        let copy = node.mesh().filter(|_| posed).map_or(0, |m| mesh_bytes[m.index()]);
        bytes = bytes.saturating_add(instances.saturating_mul(80 + copy));
    }
    for skin in document.skins() {
        bytes = bytes.saturating_add(skin.inverse_bind_matrices().map_or(0, |a| a.count() as u64 * 64));
    }
    for animation in document.animations() {
        for channel in animation.channels() {
            let sampler = channel.sampler();
            bytes = bytes.saturating_add((sampler.input().count() as u64 + sampler.output().count() as u64) * 16);
        }
    }
    if bytes > files::read::MAX_LOAD_GEOMETRY_BYTES {
        return Err(format!(
            "its accessors expand to {} of vertices, indices and keyframes, over the {} one scene may hold; give a smaller scene",
            files::read::human_bytes(bytes),
            files::read::human_bytes(files::read::MAX_LOAD_GEOMETRY_BYTES)
        ));
    }
    Ok(())
}

/// A glTF file's error; a reason that does not say how to fix it gets the way every malformed file
/// is fixed.
fn gltf_error(path: &Path, reason: String) -> Error {
    let reason = crate::error::one_line(&reason);
    let reason = if reason.contains("; ") {
        reason
    } else {
        format!("{reason}; re-export the file from its authoring tool, or check it with the Khronos glTF Validator")
    };
    Error::Gltf { path: path.to_owned(), reason }
}

/// Checks what the gltf crate's validation reads without checking: a primitive's POSITION accessor,
/// which it indexes directly.
fn check_before_validation(json: &::gltf::json::Root) -> Result<(), String> {
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            for (semantic, accessor) in &primitive.attributes {
                if accessor.value() >= json.accessors.len() {
                    return Err(format!(
                        "mesh {m} primitive {p}: {} names accessor {}, and the file has {} accessors",
                        semantic.to_string(),
                        accessor.value(),
                        json.accessors.len()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// The validator's first complaint, with where to look.
fn validation_reason(error: ::gltf::Error) -> String {
    match error {
        ::gltf::Error::Validation(errors) => {
            let shown: Vec<String> = errors.iter().take(3).map(|(path, e)| format!("{path}: {e}")).collect();
            let more = if errors.len() > 3 { format!(" (and {} more)", errors.len() - 3) } else { String::new() };
            format!("{}{more}; fix these fields or re-export the file", shown.join("; "))
        }
        e => e.to_string(),
    }
}

/// The file parsed (not validated), retried once, where the gltf crate's JSON types refuse it, with
/// what glTF leaves optional and they require taken care of (`optional_members_filled`); the first
/// error stands if that does not help.
fn parse(bytes: &[u8]) -> std::result::Result<::gltf::Gltf, ::gltf::Error> {
    let error = match ::gltf::Gltf::from_slice_without_validation(bytes) {
        Ok(gltf) => return Ok(gltf),
        Err(error) => error,
    };
    match optional_members_filled(bytes) {
        Some(filled) => ::gltf::Gltf::from_slice_without_validation(&filled).map_err(|_| error),
        None => Err(error),
    }
}

/// The file (a .gltf's JSON, or a GLB with its JSON chunk rewritten) with a scene's absent `nodes`
/// made empty, and animation channels that target no node (`KHR_animation_pointer`'s, which are not
/// played) left out, with a warning; `None` where neither applies.
fn optional_members_filled(bytes: &[u8]) -> Option<Vec<u8>> {
    let glb = bytes.starts_with(b"glTF");
    if glb && bytes.get(16..20) != Some(b"JSON") {
        return None;
    }
    let json_range = if glb { 20..20 + u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize } else { 0..bytes.len() };
    let mut root: serde_json::Value = serde_json::from_slice(bytes.get(json_range.clone())?).ok()?;
    let mut changed = false;
    for scene in root.get_mut("scenes").and_then(serde_json::Value::as_array_mut).into_iter().flatten() {
        if let Some(scene) = scene.as_object_mut().filter(|s| !s.contains_key("nodes")) {
            scene.insert("nodes".into(), serde_json::Value::Array(Vec::new()));
            changed = true;
        }
    }
    let mut dropped = 0;
    for animation in root.get_mut("animations").and_then(serde_json::Value::as_array_mut).into_iter().flatten() {
        if let Some(channels) = animation.get_mut("channels").and_then(serde_json::Value::as_array_mut) {
            let before = channels.len();
            channels.retain(|c| c.get("target").is_none_or(|t| t.get("node").is_some()));
            dropped += before - channels.len();
        }
    }
    if dropped > 0 {
        log::warn!("{dropped} animation channel(s) target no node (KHR_animation_pointer): they are not played");
        changed = true;
    }
    if !changed {
        return None;
    }
    let mut json = serde_json::to_vec(&root).ok()?;
    if !glb {
        return Some(json);
    }
    json.resize(json.len().next_multiple_of(4), b' ');
    let rest = bytes.get(json_range.end..)?;
    let mut filled = Vec::with_capacity(20 + json.len() + rest.len());
    filled.extend_from_slice(&bytes[..8]);
    filled.extend_from_slice(&((20 + json.len() + rest.len()) as u32).to_le_bytes());
    filled.extend_from_slice(&(json.len() as u32).to_le_bytes());
    filled.extend_from_slice(b"JSON");
    filled.extend_from_slice(&json);
    filled.extend_from_slice(rest);
    Some(filled)
}

/// The parser's reason, with the detail its GLB messages leave out.
fn parse_reason(error: ::gltf::Error) -> String {
    use ::gltf::binary::Error as Glb;
    match error {
        ::gltf::Error::Binary(Glb::Length { length, length_read }) => {
            format!("the GLB header declares {length} bytes of content but only {length_read} follow it; the file is truncated")
        }
        ::gltf::Error::Binary(e) => format!("corrupt GLB container: {e}"),
        ::gltf::Error::Deserialize(e) => format!("invalid glTF JSON: {e}"),
        e => e.to_string(),
    }
}

/// Refuses a file that requires an extension the importer does not honour, and names, once each in a
/// warning, those it only uses: what they add to the file is ignored, never silently.
fn check_extensions(path: &Path, document: &Document) -> Result<()> {
    if let Some(extension) = document.extensions_required().find(|e| !SUPPORTED_EXTENSIONS.contains(e)) {
        return Err(Error::UnsupportedGltfExtension {
            path: path.to_owned(),
            extension: extension.to_owned(),
            supported: SUPPORTED_EXTENSIONS.join(", "),
        });
    }
    for extension in document.extensions_used().filter(|e| !SUPPORTED_EXTENSIONS.contains(e)) {
        log::warn!(
            "{}: the glTF extension {extension} is not supported, so what it adds is ignored (supported: {})",
            path.display(),
            SUPPORTED_EXTENSIONS.join(", ")
        );
    }
    Ok(())
}

/// Where a URI's bytes come from.
enum UriSource<'a> {
    /// A `data:` URI's media type (if any) and base64 payload.
    Data {
        media_type: Option<&'a str>,
        base64: &'a str,
    },
    File(PathBuf),
}

/// Resolves a URI as the gltf crate does: `data:`, `file:` and relative paths (percent-decoded).
fn resolve_uri<'a>(uri: &'a str, base: &Path) -> Result<UriSource<'a>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        return Ok(match rest.split_once(";base64,") {
            Some((media_type, base64)) => UriSource::Data { media_type: Some(media_type), base64 },
            None => UriSource::Data { media_type: None, base64: rest },
        });
    }
    if let Some(path) = uri.strip_prefix("file://").or_else(|| uri.strip_prefix("file:")) {
        return Ok(UriSource::File(PathBuf::from(path)));
    }
    if uri.contains(':') {
        return Err(format!("URI `{uri}` has a scheme manylights cannot read; give a relative path, a file: or a data: URI"));
    }
    let decoded = percent_decode(uri).ok_or_else(|| format!("URI `{uri}` does not percent-decode to UTF-8"))?;
    Ok(UriSource::File(base.join(decoded)))
}

/// A data URI's bytes, counted against the load's budget.
fn decode_data_uri(base64: &str, gltf: &Path, budget: &LoadBudget) -> Result<Vec<u8>> {
    budget.take_input(base64.len() as u64 / 4 * 3, gltf)?;
    ::base64::decode(base64).map_err(|e| gltf_error(gltf, format!("a data URI is not valid base64: {e}")))
}

/// Reads every buffer: the GLB binary chunk, data URIs, or files up to their declared byte length.
fn load_buffers(
    gltf: &Path,
    root: &::gltf::json::Root,
    base: &Path,
    mut blob: Option<Vec<u8>>,
    budget: &LoadBudget,
) -> Result<Vec<buffer::Data>> {
    let invalid = |reason: String| gltf_error(gltf, reason);
    root.buffers
        .iter()
        .enumerate()
        .map(|(index, buffer)| {
            let length = buffer.byte_length.0 as usize;
            if let Some(length) = compression::fallback_length(buffer) {
                budget.take_input(length as u64, gltf)?;
                return Ok(buffer::Data(vec![0; length.next_multiple_of(4)]));
            }
            let (what, mut data) = match &buffer.uri {
                None => {
                    let what = "the GLB binary chunk".to_owned();
                    let data = blob.take().ok_or_else(|| invalid(format!("buffer {index} ({what}): the file has no binary chunk")))?;
                    (what, data)
                }
                Some(uri) => match resolve_uri(uri, base).map_err(|e| invalid(format!("buffer {index}: {e}")))? {
                    UriSource::Data { base64, .. } => ("a data URI".to_owned(), decode_data_uri(base64, gltf, budget)?),
                    UriSource::File(file) => {
                        (format!("`{uri}`"), files::read_input(&file, InputKind::Buffer, Some(length as u64), budget)?)
                    }
                },
            };
            if data.len() < length {
                return Err(invalid(format!(
                    "buffer {index} ({what}) has {} bytes, the file declares {length}; the file is truncated or its byteLength is wrong",
                    data.len()
                )));
            }
            // As the gltf crate pads them.
            data.resize(data.len().next_multiple_of(4), 0);
            Ok(buffer::Data(data))
        })
        .collect()
}

/// Checks what the gltf crate's validation leaves out but its loaders would panic on: images without
/// a source, URIs whose percent-decoding is not UTF-8, empty accessors.
fn check_sources(document: &Document) -> Result<(), String> {
    let json = document.as_json();
    for (i, image) in json.images.iter().enumerate() {
        if image.buffer_view.is_some() && image.mime_type.is_none() {
            return Err(format!("image {i} has a bufferView but no mimeType"));
        }
        if image.buffer_view.is_none() && image.uri.is_none() {
            return Err(format!("image {i} has neither a uri nor a bufferView"));
        }
    }
    let uris = json.buffers.iter().filter_map(|b| b.uri.as_deref());
    let uris = uris.chain(json.images.iter().filter_map(|i| i.uri.as_deref()));
    for uri in uris.filter(|u| !u.starts_with("data:")) {
        if percent_decode(uri).is_none() {
            return Err(format!("URI `{uri}` does not percent-decode to UTF-8"));
        }
    }
    // The gltf crate's validation leaves channel targets unchecked, and `target().node()` unwraps.
    for (a, animation) in json.animations.iter().enumerate() {
        for (c, channel) in animation.channels.iter().enumerate() {
            let node = channel.target.node.value();
            if node >= json.nodes.len() {
                return Err(format!(
                    "animation {a} channel {c}: target node {node} does not exist (the file has {} nodes)",
                    json.nodes.len()
                ));
            }
        }
    }
    if let Some(accessor) = document.accessors().find(|a| a.count() == 0) {
        return Err(format!("accessor {} has count 0", accessor.index()));
    }
    // The gltf crate's sparse reader underflows on a count of 0 and reads past the accessor beyond it.
    for accessor in document.accessors() {
        if let Some(sparse) = accessor.sparse() {
            if sparse.count() == 0 || sparse.count() > accessor.count() {
                return Err(format!(
                    "accessor {}: sparse count {} must be 1 to the accessor's count {}",
                    accessor.index(),
                    sparse.count(),
                    accessor.count()
                ));
            }
        }
    }
    Ok(())
}

/// A relative URI's path: `%XX` escapes decoded (a `%` without two hex digits after it stays), or
/// `None` when the result is not UTF-8.
fn percent_decode(uri: &str) -> Option<String> {
    let mut bytes = Vec::with_capacity(uri.len());
    let mut rest = uri.as_bytes();
    while let Some((&first, tail)) = rest.split_first() {
        let escaped =
            (first == b'%').then(|| tail.get(..2)).flatten().and_then(|hex| u8::from_str_radix(std::str::from_utf8(hex).ok()?, 16).ok());
        match escaped {
            Some(byte) => {
                bytes.push(byte);
                rest = &tail[2..];
            }
            None => {
                bytes.push(first);
                rest = tail;
            }
        }
    }
    String::from_utf8(bytes).ok()
}

/// Checks that every buffer view lies inside its buffer: the gltf crate slices images out of them
/// without checking.
fn check_views(document: &Document, buffers: &[buffer::Data]) -> Result<(), String> {
    for view in document.views() {
        let buffer_len = buffers.get(view.buffer().index()).map_or(0, |b| b.len());
        if view.offset().checked_add(view.length()).is_none_or(|end| end > buffer_len) {
            return Err(format!(
                "buffer view {} (bytes {}..+{}) lies outside buffer {} ({buffer_len} bytes)",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index()
            ));
        }
    }
    Ok(())
}

/// Decodes every image to an RGBA8 texture, on all cores: PNG decoding dominates loading Sponza.
fn decode_images(gltf: &Path, document: &Document, base: &Path, buffers: &[buffer::Data], budget: &LoadBudget) -> Result<Vec<Texture>> {
    let images: Vec<_> = document.images().collect();
    let workers = std::thread::available_parallelism().map_or(1, usize::from).min(images.len());
    let next = AtomicUsize::new(0);
    let mut decoded: Vec<(usize, Result<Texture>)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                s.spawn(|| {
                    let mut done = Vec::new();
                    while let Some(image) = images.get(next.fetch_add(1, Ordering::Relaxed)) {
                        // Each worker guards its own decoding: a guard holds for its thread only.
                        let texture = guard::contain_panics(|| decode_image(gltf, image, base, buffers, budget))
                            .unwrap_or_else(|message| Err(Error::ParserPanic { path: gltf.to_owned(), parser: "image decoder", message }));
                        done.push((image.index(), texture));
                    }
                    done
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic))).collect()
    });
    decoded.sort_by_key(|(index, _)| *index);
    decoded.into_iter().map(|(_, texture)| texture).collect()
}

/// Extensions whose texture objects name an image of their own format (`source`).
const TEXTURE_SOURCE_EXTENSIONS: [&str; 2] = ["EXT_texture_webp", "KHR_texture_basisu"];

/// A KTX2 file's first bytes.
const KTX2_MAGIC: [u8; 12] = [0xAB, b'K', b'T', b'X', b' ', b'2', b'0', 0xBB, b'\r', b'\n', 0x1A, b'\n'];

/// PNG, JPEG or WebP (`EXT_texture_webp`), as the gltf crate chooses: the media type, else the
/// file's extension, else its first bytes.
fn image_format(media_type: Option<&str>, uri: Option<&str>, bytes: &[u8]) -> Option<image::ImageFormat> {
    use image::ImageFormat::{Jpeg, Png, WebP};
    let by_media_type = match media_type {
        Some("image/png") => Some(Png),
        Some("image/jpeg") => Some(Jpeg),
        Some("image/webp") => Some(WebP),
        _ => None,
    };
    let by_extension = || match uri?.rsplit('.').next()?.to_ascii_lowercase().as_str() {
        "png" => Some(Png),
        "jpg" | "jpeg" => Some(Jpeg),
        "webp" => Some(WebP),
        _ => None,
    };
    let by_content = || image::guess_format(bytes).ok().filter(|f| matches!(f, Png | Jpeg | WebP));
    by_media_type.or_else(|| media_type.is_none().then(by_extension).flatten()).or_else(by_content)
}

fn decode_image(gltf: &Path, image: &::gltf::Image, base: &Path, buffers: &[buffer::Data], budget: &LoadBudget) -> Result<Texture> {
    let file_uri = match image.source() {
        ::gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => Some(uri),
        _ => None,
    };
    // A file name is the most recognisable label; embedded images fall back to their name or index.
    let name = file_uri
        .map(|u| u.rsplit('/').next().unwrap_or(u))
        .or(image.name())
        .map_or_else(|| format!("image {}", image.index()), str::to_owned);
    let invalid = |reason: String| gltf_error(gltf, format!("image {} ({name}): {reason}", image.index()));
    let (bytes, media_type, uri): (std::borrow::Cow<[u8]>, Option<&str>, Option<&str>) = match image.source() {
        ::gltf::image::Source::View { view, mime_type } => {
            let data = &buffers[view.buffer().index()].0;
            (data[view.offset()..view.offset() + view.length()].into(), Some(mime_type), None)
        }
        ::gltf::image::Source::Uri { uri, mime_type } => match resolve_uri(uri, base).map_err(&invalid)? {
            UriSource::Data { media_type, base64 } => (decode_data_uri(base64, gltf, budget)?.into(), media_type.or(mime_type), None),
            UriSource::File(file) => (files::read_input(&file, InputKind::Image, None, budget)?.into(), mime_type, Some(uri)),
        },
    };
    if media_type == Some("image/ktx2") || bytes.starts_with(&KTX2_MAGIC) {
        let (width, height, rgba8) = decode_ktx2(&bytes, budget).map_err(invalid)?;
        return Ok(Texture { name, width, height, rgba8 });
    }
    let format = image_format(media_type, uri, &bytes)
        .ok_or_else(|| invalid("not a PNG, JPEG, WebP or KTX2 image; convert it to PNG or JPEG".to_owned()))?;
    let decoded = decode_limited(&bytes, format, budget).map_err(invalid)?;
    Ok(Texture { name, width: decoded.width, height: decoded.height, rgba8: to_rgba8(decoded) })
}

/// A KTX2 texture's base level as RGBA8, as stored (sRGB-encoded colour stays encoded, as PNG's
/// does): Basis Universal (`KHR_texture_basisu`) transcoded, or a plain 8-bit format, within the
/// load's budget.
fn decode_ktx2(bytes: &[u8], budget: &LoadBudget) -> Result<(u32, u32, Vec<u8>), String> {
    let reader = ktx2::Reader::new(bytes).map_err(|e| format!("the KTX2 file does not parse ({e}); re-export it, or give a PNG"))?;
    match reader.header().format {
        None => decode_basis(bytes, budget),
        Some(format) => decode_plain_ktx2(&reader, format, budget),
    }
}

/// A 2D KTX2 texture in an 8-bit format of one to four channels (UNORM or sRGB), uncompressed or
/// in Zstandard, expanded to RGBA8 as a sampler reads the format (missing colour channels 0, missing
/// alpha opaque).
fn decode_plain_ktx2(reader: &ktx2::Reader<&[u8]>, format: ktx2::Format, budget: &LoadBudget) -> Result<(u32, u32, Vec<u8>), String> {
    use ktx2::{Format, SupercompressionScheme};
    let header = reader.header();
    let unreadable = || {
        format!("the KTX2 image's format {format:?} is not one manylights reads (8-bit R, RG, RGB or RGBA, or Basis Universal); give a PNG")
    };
    let channels = match format {
        Format::R8_UNORM | Format::R8_SRGB => 1,
        Format::R8G8_UNORM | Format::R8G8_SRGB => 2,
        Format::R8G8B8_UNORM | Format::R8G8B8_SRGB => 3,
        Format::R8G8B8A8_UNORM | Format::R8G8B8A8_SRGB => 4,
        _ => return Err(unreadable()),
    };
    if header.pixel_depth > 1 || header.layer_count > 1 || header.face_count != 1 {
        return Err("the KTX2 image is not a single 2D image (it is 3D, an array or a cube map); give a 2D texture".into());
    }
    let (width, height) = (header.pixel_width, header.pixel_height.max(1));
    let size = u64::from(width) * u64::from(height) * 4;
    if size > super::IMAGE_DECODE_LIMIT_MIB * 1024 * 1024 {
        return Err(format!(
            "the image is too large to decode ({width}×{height}; the decoder allows {} MiB); give a smaller one",
            super::IMAGE_DECODE_LIMIT_MIB
        ));
    }
    budget.take_decoded(size * 2).map_err(|e| e.to_string())?;
    let level = reader.levels().next().ok_or("the KTX2 image has no levels; re-export it")?;
    let stored = size / 4 * channels;
    let texels = match header.supercompression_scheme {
        None => std::borrow::Cow::Borrowed(level.data),
        Some(SupercompressionScheme::Zstandard) => {
            use std::io::Read;
            let mut decoder = ruzstd::streaming_decoder::StreamingDecoder::new(level.data)
                .map_err(|e| format!("the KTX2 image's Zstandard data does not decode ({e})"))?;
            let mut texels = Vec::with_capacity(stored as usize);
            (&mut decoder)
                .take(stored + 1)
                .read_to_end(&mut texels)
                .map_err(|e| format!("the KTX2 image's Zstandard data does not decode ({e})"))?;
            std::borrow::Cow::Owned(texels)
        }
        Some(scheme) => {
            return Err(format!("the KTX2 image's supercompression {scheme:?} is not one manylights reads (none or Zstandard); give a PNG"))
        }
    };
    if texels.len() as u64 != stored {
        return Err(format!(
            "the KTX2 image's base level holds {} bytes where {width}×{height} {format:?} takes {stored}; re-export it",
            texels.len()
        ));
    }
    // Missing channels as a sampler reads the format: red alone is (r, 0, 0, 1), not grey.
    let rgba8 = texels
        .chunks_exact(channels as usize)
        .flat_map(|texel| {
            let mut rgba = [0, 0, 0, 255];
            rgba[..texel.len()].copy_from_slice(texel);
            rgba
        })
        .collect();
    Ok((width, height, rgba8))
}

/// A KTX2 texture in Basis Universal (`KHR_texture_basisu`): its base level transcoded to RGBA8 on
/// the CPU.
fn decode_basis(bytes: &[u8], budget: &LoadBudget) -> Result<(u32, u32, Vec<u8>), String> {
    let not_basis = |e: basisu::Error| {
        format!("the KTX2 image is not a Basis Universal texture manylights can transcode ({e:?}); encode it with ETC1S or UASTC, or give a PNG")
    };
    let transcoder = basisu::Transcoder::new(bytes).map_err(not_basis)?;
    let (width, height) = transcoder.base_dimensions();
    let size = u64::from(width) * u64::from(height) * 4;
    if size > super::IMAGE_DECODE_LIMIT_MIB * 1024 * 1024 {
        return Err(format!(
            "the image is too large to decode ({width}×{height}; the decoder allows {} MiB); give a smaller one",
            super::IMAGE_DECODE_LIMIT_MIB
        ));
    }
    budget.take_decoded(size).map_err(|e| e.to_string())?;
    let rgba8 = transcoder.transcode(0, basisu::TargetFormat::Rgba32, basisu::DecodeFlags::NONE).map_err(not_basis)?;
    Ok((width, height, rgba8))
}

/// Decodes an image under the decoder's allocation limit and the load's budget for decoded images.
pub(crate) fn decode_limited(bytes: &[u8], format: image::ImageFormat, budget: &LoadBudget) -> Result<::gltf::image::Data, String> {
    use image::{DynamicImage, ImageDecoder};
    let too_large = |e: image::ImageError| match e {
        image::ImageError::Limits(_) => {
            format!("{e}: the image is too large to decode (the decoder allows {} MiB); give a smaller one", super::IMAGE_DECODE_LIMIT_MIB)
        }
        e => crate::error::one_line(&e.to_string()),
    };
    let mut decoder = image::ImageReader::with_format(std::io::Cursor::new(bytes), format).into_decoder().map_err(too_large)?;
    let (width, height) = decoder.dimensions();
    // As `ImageReader::decode` checks, before the decoder allocates: the decoded image within the
    // decoder's limit, and it and its RGBA8 copy within the load's budget.
    let mut limits = image::Limits::default();
    limits.reserve(decoder.total_bytes()).map_err(too_large)?;
    decoder.set_limits(limits).map_err(too_large)?;
    budget.take_decoded(decoder.total_bytes().saturating_add(u64::from(width) * u64::from(height) * 4))?;
    let image = DynamicImage::from_decoder(decoder).map_err(too_large)?;
    use ::gltf::image::Format::*;
    let format = match image {
        DynamicImage::ImageLuma8(_) => R8,
        DynamicImage::ImageLumaA8(_) => R8G8,
        DynamicImage::ImageRgb8(_) => R8G8B8,
        DynamicImage::ImageRgba8(_) => R8G8B8A8,
        DynamicImage::ImageLuma16(_) => R16,
        DynamicImage::ImageLumaA16(_) => R16G16,
        DynamicImage::ImageRgb16(_) => R16G16B16,
        DynamicImage::ImageRgba16(_) => R16G16B16A16,
        DynamicImage::ImageRgb32F(_) => R32G32B32FLOAT,
        DynamicImage::ImageRgba32F(_) => R32G32B32A32FLOAT,
        other => return Err(format!("pixel format {:?} is not supported; save the image as 8- or 16-bit RGB(A)", other.color())),
    };
    Ok(::gltf::image::Data { format, width, height, pixels: image.into_bytes() })
}

/// Expands any decoded pixel format to 8-bit RGBA: grey replicates to RGB, missing alpha is opaque,
/// 16-bit and float channels are rescaled to 0..=255.
pub(crate) fn to_rgba8(data: ::gltf::image::Data) -> Vec<u8> {
    use ::gltf::image::Format::*;
    let (channels, size) = match data.format {
        R8G8B8A8 => return data.pixels,
        R8 => (1, 1),
        R8G8 => (2, 1),
        R8G8B8 => (3, 1),
        R16 => (1, 2),
        R16G16 => (2, 2),
        R16G16B16 => (3, 2),
        R16G16B16A16 => (4, 2),
        R32G32B32FLOAT => (3, 4),
        R32G32B32A32FLOAT => (4, 4),
    };
    let unorm8 = |c: &[u8]| match size {
        1 => c[0],
        2 => ((u32::from(u16::from_ne_bytes([c[0], c[1]])) + 128) / 257) as u8,
        _ => (f32::from_ne_bytes([c[0], c[1], c[2], c[3]]).clamp(0.0, 1.0) * 255.0).round() as u8,
    };
    let mut rgba = Vec::with_capacity(data.pixels.len() / (channels * size) * 4);
    for pixel in data.pixels.chunks_exact(channels * size) {
        let c = |i: usize| unorm8(&pixel[i * size..(i + 1) * size]);
        rgba.extend(match channels {
            1 => [c(0), c(0), c(0), 255],
            2 => [c(0), c(0), c(0), c(1)],
            3 => [c(0), c(1), c(2), 255],
            _ => [c(0), c(1), c(2), c(3)],
        });
    }
    rgba
}

fn build_scene(document: &Document, buffers: &[buffer::Data], textures: Vec<Texture>) -> Result<Scene, String> {
    let mut materials: Vec<Material> = document.materials().map(|m| material(&m, document)).collect::<Result<_, _>>()?;
    // Primitives without a material use the glTF default material, appended only when needed.
    let default_material = materials.len();
    let (meshes, sources): (Vec<Mesh>, Vec<_>) =
        document.meshes().map(|m| mesh(&m, buffers, &materials, default_material)).collect::<Result<Vec<_>, _>>()?.into_iter().unzip();
    if meshes.iter().flat_map(|m| &m.primitives).any(|p| p.material == default_material) {
        materials.push(Material::default());
    }
    let mut textures = textures;
    roughness_from_glossiness(document, &mut materials, &mut textures);
    let mut scene = Scene { meshes, materials, textures, ..Scene::default() };
    match document.default_scene().or_else(|| document.scenes().next()) {
        Some(root) => {
            let hierarchy = place_nodes(&mut scene, &root, document, buffers)?;
            let (animation, weight_keys) = node_animation(document, buffers, &hierarchy)?;
            scene.animation = animation;
            scene.deformers = poses(document, buffers, &mut scene, &hierarchy, &sources, weight_keys)?;
        }
        None => log::warn!("the glTF file has no scene: nothing is placed"),
    }
    scene.authored_lights = scene.lights.len();
    Ok(scene)
}

/// The placed node hierarchy, for animation: nodes in the order visited (parents first), each
/// glTF node's place in it, and for each mesh instance the node it was placed by (its place, and
/// the glTF node).
struct Hierarchy {
    nodes: Vec<animation::Node>,
    index_of: Vec<Option<usize>>,
    instance_nodes: Vec<usize>,
    instance_sources: Vec<usize>,
}

/// Morph weights keyframed by the animation, by glTF node.
type WeightKeysByNode = Vec<Option<pose::WeightKeys>>;

/// The file's first animation, as the node animation of the moving instances and the skins' joints,
/// and the morph weights it keys; no animation where none moves an instance and no mesh is skinned.
fn node_animation(
    document: &Document,
    buffers: &[buffer::Data],
    hierarchy: &Hierarchy,
) -> Result<(Option<animation::Animation>, WeightKeysByNode), String> {
    let mut weight_keys = vec![None; document.nodes().len()];
    let mut channels = Vec::new();
    let mut name = String::from("rest pose");
    if let Some(source) = document.animations().next() {
        if document.animations().len() > 1 {
            log::warn!("the glTF file has {} animations: only the first plays", document.animations().len());
        }
        name = source.name().map_or_else(|| format!("animation {}", source.index()), str::to_owned);
        for channel in source.channels() {
            // Channels of nodes outside the scene move nothing placed.
            let target = channel.target().node();
            let Some(node) = hierarchy.index_of[target.index()] else { continue };
            let sampler = channel.sampler();
            let at = |what: &str| format!("{name}: channel {} {what}", channel.index());
            check_accessor(&sampler.input(), &at("keyframe times"), Dimensions::Scalar, FLOATS)?;
            let (dimensions, types) = match channel.target().property() {
                ::gltf::animation::Property::Translation | ::gltf::animation::Property::Scale => (Dimensions::Vec3, FLOATS),
                ::gltf::animation::Property::Rotation => (Dimensions::Vec4, SIGNED_NORMALIZED),
                ::gltf::animation::Property::MorphTargetWeights => (Dimensions::Scalar, SIGNED_NORMALIZED),
            };
            check_accessor(&sampler.output(), &at("keyframe values"), dimensions, types)?;
            let reader = channel.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let times: Vec<f32> =
                reader.read_inputs().ok_or_else(|| format!("{name}: channel {} has no keyframe times", channel.index()))?.collect();
            let interpolation = match channel.sampler().interpolation() {
                ::gltf::animation::Interpolation::Step => animation::Interpolation::Step,
                ::gltf::animation::Interpolation::Linear => animation::Interpolation::Linear,
                ::gltf::animation::Interpolation::CubicSpline => animation::Interpolation::CubicSpline,
            };
            let to_vec4 = |v: [f32; 3]| Vec3::from(v).extend(0.0);
            let (property, values): (_, Vec<Vec4>) = match reader.read_outputs() {
                Some(ReadOutputs::Translations(values)) => (animation::Property::Translation, values.map(to_vec4).collect()),
                Some(ReadOutputs::Scales(values)) => (animation::Property::Scale, values.map(to_vec4).collect()),
                Some(ReadOutputs::Rotations(values)) => (animation::Property::Rotation, values.into_f32().map(Vec4::from).collect()),
                Some(ReadOutputs::MorphTargetWeights(values)) => {
                    weight_keys[target.index()] = Some(pose::WeightKeys { interpolation, times, values: values.into_f32().collect() });
                    continue;
                }
                None => return Err(format!("{name}: channel {} has no keyframe values", channel.index())),
            };
            channels.push(animation::Channel { node, property, interpolation, times, values });
        }
    }
    // An instance moves when its node or an ancestor is animated; a skinned one is placed by its
    // joints instead (glTF ignores its node's transform).
    let mut moving = vec![false; hierarchy.nodes.len()];
    for channel in &channels {
        moving[channel.node] = true;
    }
    for (i, node) in hierarchy.nodes.iter().enumerate() {
        moving[i] |= node.parent.is_some_and(|p| moving[p]);
    }
    let skinned = |instance: usize| document.nodes().nth(hierarchy.instance_sources[instance]).is_some_and(|n| n.skin().is_some());
    let instances: Vec<(usize, usize)> =
        hierarchy.instance_nodes.iter().copied().enumerate().filter(|&(i, node)| moving[node] && !skinned(i)).collect();
    let any_skinned = (0..hierarchy.instance_nodes.len()).any(skinned);
    if instances.is_empty() && !any_skinned && weight_keys.iter().all(Option::is_none) {
        return Ok((None, weight_keys));
    }
    let weight_times = weight_keys.iter().flatten().filter_map(|k| k.times.last().copied());
    let duration = channels.iter().filter_map(|c| c.times.last().copied()).chain(weight_times).fold(0.0, f32::max);
    let animation = animation::Animation { name, nodes: hierarchy.nodes.clone(), channels, instances, duration };
    animation.validate(hierarchy.instance_nodes.len())?;
    Ok((Some(animation), weight_keys))
}

/// The deformers of the placed instances whose node has a skin or whose mesh has morph targets. Each
/// such instance gets a mesh of its own (a copy where other instances use the mesh too), since its
/// pose is its node's.
fn poses(
    document: &Document,
    buffers: &[buffer::Data],
    scene: &mut Scene,
    hierarchy: &Hierarchy,
    sources: &[Vec<Vec<u32>>],
    weight_keys: WeightKeysByNode,
) -> Result<Vec<Deformer>, String> {
    let mut deformers = Vec::new();
    let mut users = vec![0usize; scene.meshes.len()];
    for instance in &scene.instances {
        users[instance.mesh] += 1;
    }
    for (instance, &source) in hierarchy.instance_sources.iter().enumerate() {
        let node = document.nodes().nth(source).expect("placed nodes exist");
        let gltf_mesh = node.mesh().expect("instances are placed by mesh nodes");
        let targets = gltf_mesh.primitives().map(|p| p.morph_targets().len()).max().unwrap_or(0);
        if node.skin().is_none() && targets == 0 {
            continue;
        }
        let at = format!("node {} (mesh {})", node.index(), gltf_mesh.index());
        let mut mesh = scene.instances[instance].mesh;
        if users[mesh] > 1 {
            users[mesh] -= 1;
            scene.meshes.push(scene.meshes[mesh].clone());
            mesh = scene.meshes.len() - 1;
            scene.instances[instance].mesh = mesh;
        }
        let rest_weights = node.weights().or(gltf_mesh.weights()).map_or_else(|| vec![0.0; targets], <[f32]>::to_vec);
        if rest_weights.len() != targets {
            return Err(format!("{at}: {} morph weights for {targets} morph targets; give one weight per target", rest_weights.len()));
        }
        // GPU instances of one node share its keyed weights.
        let keys = weight_keys[source].clone();
        if let Some(keys) = &keys {
            let per_key = if keys.interpolation == animation::Interpolation::CubicSpline { 3 } else { 1 } * targets;
            if keys.values.len() != per_key * keys.times.len() {
                return Err(format!(
                    "{at}: the animation keys {} morph weights for {} keyframes of {targets} targets; give {per_key} per keyframe",
                    keys.values.len(),
                    keys.times.len()
                ));
            }
        }
        let mut pose = pose::Pose { targets: vec![Vec::new(); targets], rest_weights, weight_keys: keys, skin: None };
        let mut skin_data: Option<pose::Skin> = None;
        if let Some(skin) = node.skin() {
            let joints = skin
                .joints()
                .map(|j| {
                    hierarchy.index_of[j.index()]
                        .ok_or_else(|| format!("{at}: skin {} joint node {} is not in the scene", skin.index(), j.index()))
                })
                .collect::<Result<Vec<_>, _>>()?;
            let inverse_bind = match skin.inverse_bind_matrices() {
                Some(accessor) => {
                    check_accessor(&accessor, "inverseBindMatrices", Dimensions::Mat4, FLOATS)?;
                    if accessor.count() != joints.len() {
                        return Err(format!(
                            "{at}: skin {} has {} inverse bind matrices for {} joints",
                            skin.index(),
                            accessor.count(),
                            joints.len()
                        ));
                    }
                    let matrices: Vec<Mat4> = skin
                        .reader(|b| buffers.get(b.index()).map(|d| d.0.as_slice()))
                        .read_inverse_bind_matrices()
                        .ok_or_else(|| format!("{at}: skin {}'s inverse bind matrices lie outside their buffer", skin.index()))?
                        .map(|m| Mat4::from_cols_array_2d(&m))
                        .collect();
                    if matrices.len() != joints.len() {
                        return Err(format!(
                            "{at}: skin {} has {} inverse bind matrices for {} joints",
                            skin.index(),
                            matrices.len(),
                            joints.len()
                        ));
                    }
                    matrices
                }
                None => vec![Mat4::IDENTITY; joints.len()],
            };
            let sets =
                gltf_mesh.primitives().map(|p| (0..).take_while(|&s| p.get(&Semantic::Joints(s)).is_some()).count()).max().unwrap_or(0);
            if sets == 0 {
                return Err(format!("{at}: the node has a skin but its mesh has no JOINTS_0 and WEIGHTS_0"));
            }
            skin_data = Some(pose::Skin { joints, inverse_bind, sets, joint_indices: Vec::new(), weights: Vec::new() });
        }
        let primitives = gltf_mesh.primitives().filter(|p| matches!(p.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan));
        for (p, source) in primitives.zip(&sources[gltf_mesh.index()]) {
            let at = format!("{at} primitive {}", p.index());
            let count = p.get(&Semantic::Positions).map_or(0, |a| a.count());
            for (t, target) in p.morph_targets().enumerate() {
                let offsets = morph_offsets(&target, buffers, count).map_err(|e| format!("{at}: morph target {t}: {e}"))?;
                pose.targets[t].extend(source.iter().map(|&v| offsets[v as usize]));
            }
            // Primitives with fewer targets than the mesh's are not moved by the others.
            for target in pose.targets.iter_mut().skip(p.morph_targets().len()) {
                target.extend(std::iter::repeat_n(pose::MorphOffset::default(), source.len()));
            }
            if let Some(skin) = &mut skin_data {
                let influences = skin_influences(&p, buffers, count, skin.sets, skin.joints.len()).map_err(|e| format!("{at}: {e}"))?;
                for &v in source {
                    let range = v as usize * skin.sets..(v as usize + 1) * skin.sets;
                    skin.joint_indices.extend(influences[range.clone()].iter().map(|(j, _)| *j));
                    skin.weights.extend(influences[range].iter().map(|(_, w)| *w));
                }
            }
        }
        pose.skin = skin_data;
        if pose.skin.is_some() {
            // Skinned vertices are placed in world space by their joints, the node's transform
            // ignored; a GPU instance of the node keeps its own transform on top.
            let node_index = hierarchy.instance_nodes[instance];
            let gpu_instance = hierarchy.index_of[source] != Some(node_index);
            scene.instances[instance].world_from_local = if gpu_instance { hierarchy.nodes[node_index].rest } else { Mat4::IDENTITY };
        }
        deformers.push(Deformer { mesh, deformation: Deformation::Pose(Box::new(pose)) });
    }
    Ok(deformers)
}

/// A morph target's offsets of a primitive's `count` vertices (zero where it has no attribute).
fn morph_offsets(target: &::gltf::mesh::MorphTarget, buffers: &[buffer::Data], count: usize) -> Result<Vec<pose::MorphOffset>, String> {
    let read = |accessor: Option<Accessor>, name: &str, types| -> Result<Vec<Vec3>, String> {
        let Some(accessor) = accessor else { return Ok(vec![Vec3::ZERO; count]) };
        check_accessor(&accessor, name, Dimensions::Vec3, types)?;
        if accessor.count() != count {
            return Err(format!("{name} has {} offsets for {count} vertices", accessor.count()));
        }
        let values: Vec<[f32; 3]> = read_floats(&accessor, buffers).ok_or_else(|| format!("{name} lies outside its buffer"))?;
        if values.len() != count || values.iter().flatten().any(|c| !c.is_finite()) {
            return Err(format!("{name} has {} offsets for {count} vertices, or one is not finite", values.len()));
        }
        Ok(values.into_iter().map(Vec3::from).collect())
    };
    let positions = read(target.positions(), "POSITION", MORPH_POSITIONS)?;
    let normals = read(target.normals(), "NORMAL", DIRECTIONS)?;
    let tangents = read(target.tangents(), "TANGENT", DIRECTIONS)?;
    Ok((0..count).map(|i| pose::MorphOffset { position: positions[i], normal: normals[i], tangent: tangents[i] }).collect())
}

/// Four joints of a vertex and their weights.
type Influences = ([u32; 4], [f32; 4]);

/// A primitive's `sets` runs of four (joint, weight) per vertex for its `count` vertices, weights
/// normalised to sum to 1 (all zero stays zero).
fn skin_influences(
    p: &::gltf::Primitive,
    buffers: &[buffer::Data],
    count: usize,
    sets: usize,
    joint_count: usize,
) -> Result<Vec<Influences>, String> {
    let mut influences = vec![([0u32; 4], [0f32; 4]); count * sets];
    let reader = p.reader(|b| buffers.get(b.index()).map(|d| d.0.as_slice()));
    for set in 0..sets {
        let (Some(joints), Some(weights)) = (p.get(&Semantic::Joints(set as u32)), p.get(&Semantic::Weights(set as u32))) else {
            continue;
        };
        check_accessor(&joints, &format!("JOINTS_{set}"), Dimensions::Vec4, JOINTS)?;
        check_accessor(&weights, &format!("WEIGHTS_{set}"), Dimensions::Vec4, WEIGHTS)?;
        if joints.count() != count || weights.count() != count {
            return Err(format!(
                "JOINTS_{set} and WEIGHTS_{set} have {} and {} elements for {count} vertices",
                joints.count(),
                weights.count()
            ));
        }
        let joints: Vec<[u16; 4]> =
            reader.read_joints(set as u32).ok_or_else(|| format!("JOINTS_{set} lies outside its buffer"))?.into_u16().collect();
        let weights: Vec<[f32; 4]> =
            reader.read_weights(set as u32).ok_or_else(|| format!("WEIGHTS_{set} lies outside its buffer"))?.into_f32().collect();
        if joints.len() != count || weights.len() != count {
            return Err(format!(
                "JOINTS_{set} and WEIGHTS_{set} have {} and {} elements for {count} vertices",
                joints.len(),
                weights.len()
            ));
        }
        for (v, (j, w)) in joints.iter().zip(&weights).enumerate() {
            if let Some(bad) = j.iter().zip(w).find(|(&j, &w)| w != 0.0 && j as usize >= joint_count) {
                return Err(format!("vertex {v} names joint {} of a skin with {joint_count}", bad.0));
            }
            if !w.iter().all(|w| w.is_finite() && *w >= 0.0) {
                return Err(format!("vertex {v}'s weights {w:?} must be finite and ≥ 0"));
            }
            influences[v * sets + set] = (j.map(|j| if (j as usize) < joint_count { u32::from(j) } else { 0 }), *w);
        }
    }
    for vertex in influences.chunks_mut(sets) {
        let total: f32 = vertex.iter().flat_map(|(_, w)| w).sum();
        if total > 0.0 {
            for (_, w) in vertex.iter_mut() {
                *w = w.map(|w| w / total);
            }
        }
    }
    Ok(influences)
}

/// Walks the node hierarchy depth first, adding an instance, camera or light for each node that has
/// one; returns the hierarchy as placed, for animation.
fn place_nodes(scene: &mut Scene, root: &::gltf::Scene, document: &Document, buffers: &[buffer::Data]) -> Result<Hierarchy, String> {
    let node_count = document.nodes().len();
    let mut cameras = Vec::new();
    let mut hierarchy =
        Hierarchy { nodes: Vec::new(), index_of: vec![None; node_count], instance_nodes: Vec::new(), instance_sources: Vec::new() };
    let mut stack: Vec<(Node, Mat4, Option<usize>)> = root.nodes().map(|n| (n, Mat4::IDENTITY, None)).collect();
    stack.reverse();
    while let Some((node, parent, parent_index)) = stack.pop() {
        // Validation rules out neither cycles nor nodes with two parents, and either would place a
        // node again and again (a shared child at every level doubles the walk).
        if hierarchy.index_of[node.index()].is_some() {
            return Err(format!(
                "node {} is reached twice: the node hierarchy has a cycle or a node with two parents, and glTF nodes form trees",
                node.index()
            ));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        let index = hierarchy.nodes.len();
        // Animated nodes are given as translation, rotation and scale (glTF requires it): kept exactly.
        let (translation, rotation, scale) = node.transform().decomposed();
        let rest_trs = animation::Trs { translation: translation.into(), rotation: Quat::from_array(rotation), scale: scale.into() };
        hierarchy.nodes.push(animation::Node { parent: parent_index, rest: local, rest_trs });
        hierarchy.index_of[node.index()] = Some(index);
        if let Some(mesh) = node.mesh() {
            match gpu_instances(&node, document, buffers)? {
                None => {
                    scene.instances.push(Instance { mesh: mesh.index(), world_from_local: world });
                    hierarchy.instance_nodes.push(index);
                }
                // Each instance is a child of the node, so it moves with it.
                Some(instances) => {
                    for trs in instances {
                        scene.instances.push(Instance { mesh: mesh.index(), world_from_local: world * trs.matrix() });
                        hierarchy.instance_nodes.push(hierarchy.nodes.len());
                        hierarchy.nodes.push(animation::Node::from_trs(Some(index), trs));
                    }
                }
            }
            hierarchy.instance_sources.resize(hierarchy.instance_nodes.len(), node.index());
        }
        if let Some(camera) = node.camera() {
            cameras.push((camera.index(), place_camera(&camera, &node, world)));
        }
        if let Some(light) = node.light() {
            place_light(scene, &light, world);
        }
        let first_child = stack.len();
        stack.extend(node.children().map(|child| (child, world, Some(index))));
        stack[first_child..].reverse();
    }
    // Ordered like the file's `cameras` array, so "camera N" means the same thing in both.
    cameras.sort_by_key(|(index, _)| *index);
    scene.cameras = cameras.into_iter().map(|(_, camera)| camera).collect();
    Ok(hierarchy)
}

/// `EXT_mesh_gpu_instancing`: the node's instances, each a transform under the node's (translation,
/// rotation and scale, each defaulting to none); `None` for a node without the extension.
fn gpu_instances(node: &Node, document: &Document, buffers: &[buffer::Data]) -> Result<Option<Vec<animation::Trs>>, String> {
    let Some(ext) = node.extension_value(INSTANCING) else { return Ok(None) };
    let at = format!("node {}'s {INSTANCING}", node.index());
    let attributes = ext.get("attributes").and_then(|a| a.as_object()).ok_or_else(|| format!("{at} has no attributes"))?;
    let accessor = |name: &str, dimensions, types| -> Result<Option<Accessor>, String> {
        let Some(index) = attributes.get(name) else { return Ok(None) };
        let accessor =
            index.as_u64().and_then(|i| document.accessors().nth(i as usize)).ok_or_else(|| format!("{at}: {name} names no accessor"))?;
        check_accessor(&accessor, &format!("{at} {name}"), dimensions, types)?;
        Ok(Some(accessor))
    };
    let accessors = [
        accessor("TRANSLATION", Dimensions::Vec3, POSITIONS)?,
        accessor("ROTATION", Dimensions::Vec4, DIRECTIONS)?,
        accessor("SCALE", Dimensions::Vec3, POSITIONS)?,
    ];
    let counts: Vec<usize> = accessors.iter().flatten().map(Accessor::count).collect();
    let count = counts.iter().copied().max().ok_or_else(|| format!("{at} has no TRANSLATION, ROTATION or SCALE"))?;
    if counts.iter().any(|&c| c != count) {
        return Err(format!("{at}: its attributes have different counts {counts:?}; give each instance every attribute"));
    }
    let [translation, rotation, scale] = accessors;
    let outside = |name: &str| format!("{at}: {name} lies outside its buffer");
    let translations: Option<Vec<[f32; 3]>> = match translation {
        Some(a) => Some(read_floats(&a, buffers).ok_or_else(|| outside("TRANSLATION"))?),
        None => None,
    };
    let rotations: Option<Vec<[f32; 4]>> = match rotation {
        Some(a) => Some(read_floats(&a, buffers).ok_or_else(|| outside("ROTATION"))?),
        None => None,
    };
    let scales: Option<Vec<[f32; 3]>> = match scale {
        Some(a) => Some(read_floats(&a, buffers).ok_or_else(|| outside("SCALE"))?),
        None => None,
    };
    let read_counts = [translations.as_ref().map(Vec::len), rotations.as_ref().map(Vec::len), scales.as_ref().map(Vec::len)];
    if read_counts.iter().flatten().any(|&c| c != count) {
        return Err(format!("{at}: an attribute lies partly outside its buffer"));
    }
    let instances: Vec<animation::Trs> = (0..count)
        .map(|i| animation::Trs {
            translation: translations.as_ref().map_or(Vec3::ZERO, |t| Vec3::from(t[i])),
            rotation: rotations.as_ref().map_or(Quat::IDENTITY, |r| Quat::from_array(r[i]).normalize()),
            scale: scales.as_ref().map_or(Vec3::ONE, |s| Vec3::from(s[i])),
        })
        .collect();
    if !instances.iter().all(|t| t.translation.is_finite() && t.rotation.is_finite() && t.scale.is_finite()) {
        return Err(format!("{at}: an instance's transform is NaN, infinite or a zero rotation"));
    }
    Ok(Some(instances))
}

fn place_camera(camera: &::gltf::Camera, node: &Node, world: Mat4) -> Camera {
    // A camera's transform must be rigid; scale inherited from parents is dropped.
    let (_, rotation, translation) = world.to_scale_rotation_translation();
    let rotation = if rotation.is_finite() {
        rotation.normalize()
    } else {
        log::warn!("camera on node {}: degenerate transform, using no rotation", node.index());
        Quat::IDENTITY
    };
    let projection = match camera.projection() {
        ::gltf::camera::Projection::Perspective(p) => Projection::Perspective { yfov: p.yfov(), znear: p.znear(), zfar: p.zfar() },
        ::gltf::camera::Projection::Orthographic(o) => {
            Projection::Orthographic { xmag: o.xmag(), ymag: o.ymag(), znear: o.znear(), zfar: o.zfar() }
        }
    };
    Camera {
        name: camera.name().or(node.name()).map_or_else(|| format!("camera {}", camera.index()), str::to_owned),
        world_from_view: Mat4::from_rotation_translation(rotation, translation),
        projection,
    }
}

fn place_light(scene: &mut Scene, light: &::gltf::khr_lights_punctual::Light, world: Mat4) {
    let color = Vec3::from(light.color());
    let intensity = light.intensity();
    // Lights shine down their node's -Z.
    let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let kind = match light.kind() {
        Kind::Directional if scene.sun.is_some() => {
            log::warn!("light {}: only the first directional light is used", light.index());
            return;
        }
        Kind::Directional => {
            scene.sun = Some(Sun { direction, color, illuminance: intensity });
            return;
        }
        Kind::Point => LightKind::Point,
        Kind::Spot { inner_cone_angle, outer_cone_angle } => LightKind::Spot { inner_cone_angle, outer_cone_angle },
    };
    let range = light.range().unwrap_or_else(|| Light::range_from_cutoff(intensity, color, DEFAULT_LIGHT_CUTOFF));
    if light.range().is_none() && range <= 0.0 {
        log::warn!("light {}: no intensity and no range, skipped", light.index());
        return;
    }
    scene.lights.push(Light { kind, position: world.transform_point3(Vec3::ZERO), direction, color, intensity, range, cast_shadows: true });
}

fn material(m: &::gltf::Material, document: &Document) -> Result<Material, String> {
    let name = m.name().map_or_else(|| format!("material {}", m.index().unwrap_or_default()), str::to_owned);
    let named = m.name().map_or_else(|| name.clone(), |n| format!("material {} ({n})", m.index().unwrap_or_default()));
    // glTF bounds the factor to 0..1 and leaves brightness to the extension, which may be as bright
    // as it likes; a factor outside would otherwise render black or white without a word.
    let emissive_factor = m.emissive_factor();
    if !emissive_factor.iter().all(|c| (0.0..=1.0).contains(c)) {
        return Err(format!(
            "{named}: emissiveFactor {emissive_factor:?} must be 0 to 1 in each component; for brighter emission keep it \
             within 0 to 1 and add KHR_materials_emissive_strength"
        ));
    }
    let strength = m.emissive_strength().unwrap_or(1.0);
    if !(strength.is_finite() && strength >= 0.0) {
        return Err(format!("{named}: KHR_materials_emissive_strength {strength} must be finite and ≥ 0; give a strength ≥ 0"));
    }
    let pbr = m.pbr_metallic_roughness();
    let texture = |info: Option<::gltf::texture::Info>| {
        info.map(|i| {
            let transform = i.texture_transform().map(|t| (t.offset(), t.rotation(), t.scale(), t.tex_coord()));
            texture_ref(&i.texture(), i.tex_coord(), transform, &named)
        })
        .transpose()
    };
    // The gltf crate parses the extension on texture infos only; normal and occlusion textures' are
    // read here.
    let transform_of = |what: &str, extension: Option<&serde_json::Value>| -> Result<Option<UvTransform>, String> {
        let Some(value) = extension else { return Ok(None) };
        let parsed = ::gltf::json::deserialize::from_value::<::gltf::json::extensions::texture::TextureTransform>(value.clone())
            .map_err(|e| format!("{named}: {what} texture's KHR_texture_transform: {e}"))?;
        Ok(Some((parsed.offset.0, parsed.rotation.0, parsed.scale.0, parsed.tex_coord)))
    };
    let normal_texture = match m.normal_texture() {
        Some(t) => {
            Some(texture_ref(&t.texture(), t.tex_coord(), transform_of("normal", t.extension_value("KHR_texture_transform"))?, &named)?)
        }
        None => None,
    };
    // Baked occlusion read through other coordinates than its own would darken the wrong places, so
    // on a set past the two manylights reads it is left out instead.
    let occlusion_texture = match m.occlusion_texture() {
        Some(t) => {
            let transform = transform_of("occlusion", t.extension_value("KHR_texture_transform"))?;
            let set = transform.and_then(|t| t.3).unwrap_or(t.tex_coord());
            if set <= 1 {
                Some(texture_ref(&t.texture(), set, transform, &named)?)
            } else {
                log::warn!(
                    "{named}: the occlusion texture uses TEXCOORD_{set}; only TEXCOORD_0 and TEXCOORD_1 are read, so it is left out"
                );
                None
            }
        }
        None => None,
    };
    let occlusion_strength = m.occlusion_texture().map_or(1.0, |t| t.strength());
    if !(0.0..=1.0).contains(&occlusion_strength) {
        return Err(format!("{named}: occlusion strength {occlusion_strength} must be 0 to 1; give a strength in 0 to 1"));
    }
    let material = Material {
        base_color_factor: Vec4::from(pbr.base_color_factor()),
        base_color_texture: texture(pbr.base_color_texture())?,
        metallic_factor: pbr.metallic_factor(),
        roughness_factor: pbr.roughness_factor(),
        metallic_roughness_texture: texture(pbr.metallic_roughness_texture())?,
        normal_texture,
        normal_scale: m.normal_texture().map_or(1.0, |t| t.scale()),
        occlusion_texture,
        occlusion_strength,
        emissive_factor: Vec3::from(emissive_factor) * strength,
        emissive_texture: texture(m.emissive_texture())?,
        alpha_mode: match m.alpha_mode() {
            ::gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            ::gltf::material::AlphaMode::Mask => AlphaMode::Mask { cutoff: m.alpha_cutoff().unwrap_or(0.5) },
            ::gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        double_sided: m.double_sided(),
        unlit: m.extension_value("KHR_materials_unlit").is_some(),
        specular: specular(m, document, &named)?,
        clearcoat: clearcoat(m, document, &named)?,
        transmission: transmission(m, document, &named)?,
        sheen: sheen(m, document, &named)?,
        name,
    };
    match m.extension_value(SPECULAR_GLOSSINESS) {
        Some(ext) => specular_glossiness(material, ext, document, &named),
        None => Ok(material),
    }
}

/// `KHR_materials_pbrSpecularGlossiness` as glTF Transform's `metalRough` converts it: the diffuse
/// colour as the base colour, no metal, roughness 1 − glossiness, and the specular colour as F0
/// through `KHR_materials_specular` with an index of refraction of 0 (a reflectance of 1 scaled by
/// the colour). The texture's glossiness (alpha) is turned into roughness by
/// [`roughness_from_glossiness`], which the roughness texture here still names.
fn specular_glossiness(material: Material, ext: &serde_json::Value, document: &Document, named: &str) -> Result<Material, String> {
    let diffuse = match ext.get("diffuseFactor").and_then(serde_json::Value::as_array) {
        Some(values) => {
            let c: Vec<f32> = values.iter().filter_map(serde_json::Value::as_f64).map(|v| v as f32).collect();
            let [r, g, b, a] = c[..] else { return Err(format!("{named}: diffuseFactor {values:?} must be four numbers")) };
            Vec4::new(r, g, b, a)
        }
        None => Vec4::ONE,
    };
    let glossiness = number(ext, "glossinessFactor", 1.0);
    if !(0.0..=1.0).contains(&glossiness) {
        return Err(format!("{named}: glossinessFactor {glossiness} must be 0 to 1"));
    }
    let specular_glossiness_texture = extension_texture(ext, "specularGlossinessTexture", document, named)?;
    Ok(Material {
        base_color_factor: diffuse,
        base_color_texture: extension_texture(ext, "diffuseTexture", document, named)?,
        metallic_factor: 0.0,
        roughness_factor: if specular_glossiness_texture.is_some() { 1.0 } else { 1.0 - glossiness },
        metallic_roughness_texture: specular_glossiness_texture,
        specular: super::Specular {
            ior: 0.0,
            factor: 1.0,
            texture: None,
            color_factor: color(ext, "specularFactor", Vec3::ONE, named)?,
            color_texture: specular_glossiness_texture,
        },
        ..material
    })
}

/// Gives each specular-glossiness material with a texture a roughness image of its own (G = 1 −
/// glossiness factor × the texture's alpha; metallic B = 0), made once per image and factor.
fn roughness_from_glossiness(document: &Document, materials: &mut [Material], textures: &mut Vec<Texture>) {
    let mut made = std::collections::HashMap::new();
    for (m, material) in document.materials().zip(materials) {
        let Some(ext) = m.extension_value(SPECULAR_GLOSSINESS) else { continue };
        let Some(reference) = material.metallic_roughness_texture.as_mut() else { continue };
        let (image, glossiness) = (reference.texture, number(ext, "glossinessFactor", 1.0));
        reference.texture = *made.entry((image, glossiness.to_bits())).or_insert_with(|| {
            let source = &textures[image];
            let rgba8 = source
                .rgba8
                .chunks_exact(4)
                .flat_map(|texel| [0, (255.0 - glossiness * f32::from(texel[3])).round() as u8, 0, 255])
                .collect();
            let roughness = Texture { name: format!("{} (roughness)", source.name), width: source.width, height: source.height, rgba8 };
            textures.push(roughness);
            textures.len() - 1
        });
    }
}

/// A number member of an extension object, or its default.
fn number(object: &serde_json::Value, name: &str, default: f32) -> f32 {
    object.get(name).and_then(serde_json::Value::as_f64).map_or(default, |v| v as f32)
}

/// A colour member of an extension object (three numbers), or its default.
fn color(object: &serde_json::Value, name: &str, default: Vec3, material: &str) -> Result<Vec3, String> {
    let Some(color) = object.get(name).and_then(serde_json::Value::as_array) else { return Ok(default) };
    let c: Vec<f32> = color.iter().filter_map(serde_json::Value::as_f64).map(|v| v as f32).collect();
    let [r, g, b] = c[..] else { return Err(format!("{material}: {name} {color:?} must be three numbers")) };
    Ok(Vec3::new(r, g, b))
}

/// A texture info member of an extension object (glTF's `textureInfo`, with its own
/// `KHR_texture_transform`).
fn extension_texture(object: &serde_json::Value, name: &str, document: &Document, material: &str) -> Result<Option<TextureRef>, String> {
    let Some(info) = object.get(name) else { return Ok(None) };
    let index = info.get("index").and_then(serde_json::Value::as_u64).ok_or_else(|| format!("{material}: {name} has no texture index"))?;
    let texture =
        document.textures().nth(index as usize).ok_or_else(|| format!("{material}: {name} names texture {index}, which does not exist"))?;
    let tex_coord = info.get("texCoord").and_then(serde_json::Value::as_u64).unwrap_or(0) as u32;
    let transform = match info.get("extensions").and_then(|e| e.get("KHR_texture_transform")) {
        Some(value) => {
            let parsed = ::gltf::json::deserialize::from_value::<::gltf::json::extensions::texture::TextureTransform>(value.clone())
                .map_err(|e| format!("{material}: {name}'s KHR_texture_transform: {e}"))?;
            Some((parsed.offset.0, parsed.rotation.0, parsed.scale.0, parsed.tex_coord))
        }
        None => None,
    };
    texture_ref(&texture, tex_coord, transform, material).map(Some)
}

/// `KHR_materials_ior` and `KHR_materials_specular`.
fn specular(m: &::gltf::Material, document: &Document, named: &str) -> Result<super::Specular, String> {
    let mut specular = super::Specular::default();
    if let Some(ior) = m.extension_value("KHR_materials_ior") {
        specular.ior = number(ior, "ior", 1.5);
    }
    if let Some(ext) = m.extension_value("KHR_materials_specular") {
        specular.factor = number(ext, "specularFactor", 1.0);
        specular.texture = extension_texture(ext, "specularTexture", document, named)?;
        specular.color_factor = color(ext, "specularColorFactor", Vec3::ONE, named)?;
        specular.color_texture = extension_texture(ext, "specularColorTexture", document, named)?;
    }
    Ok(specular)
}

/// `KHR_materials_clearcoat`; none where its factor is 0 (the coat is absent).
fn clearcoat(m: &::gltf::Material, document: &Document, named: &str) -> Result<Option<super::Clearcoat>, String> {
    let Some(ext) = m.extension_value("KHR_materials_clearcoat") else { return Ok(None) };
    let factor = number(ext, "clearcoatFactor", 0.0);
    if factor == 0.0 {
        return Ok(None);
    }
    let normal_scale = ext.get("clearcoatNormalTexture").map_or(1.0, |t| number(t, "scale", 1.0));
    Ok(Some(super::Clearcoat {
        factor,
        texture: extension_texture(ext, "clearcoatTexture", document, named)?,
        roughness_factor: number(ext, "clearcoatRoughnessFactor", 0.0),
        roughness_texture: extension_texture(ext, "clearcoatRoughnessTexture", document, named)?,
        normal_texture: extension_texture(ext, "clearcoatNormalTexture", document, named)?,
        normal_scale,
    }))
}

/// `KHR_materials_sheen`; none where its colour is black (the specification's off switch).
fn sheen(m: &::gltf::Material, document: &Document, named: &str) -> Result<Option<super::Sheen>, String> {
    let Some(ext) = m.extension_value("KHR_materials_sheen") else { return Ok(None) };
    let color_factor = color(ext, "sheenColorFactor", Vec3::ZERO, named)?;
    if color_factor == Vec3::ZERO {
        return Ok(None);
    }
    Ok(Some(super::Sheen {
        color_factor,
        color_texture: extension_texture(ext, "sheenColorTexture", document, named)?,
        roughness_factor: number(ext, "sheenRoughnessFactor", 0.0),
        roughness_texture: extension_texture(ext, "sheenRoughnessTexture", document, named)?,
    }))
}

/// `KHR_materials_transmission` with its medium (`KHR_materials_volume`, `KHR_materials_dispersion`);
/// none where its factor is 0.
fn transmission(m: &::gltf::Material, document: &Document, named: &str) -> Result<Option<super::Transmission>, String> {
    let Some(ext) = m.extension_value("KHR_materials_transmission") else { return Ok(None) };
    let factor = number(ext, "transmissionFactor", 0.0);
    let texture = extension_texture(ext, "transmissionTexture", document, named)?;
    if factor == 0.0 {
        return Ok(None);
    }
    let mut transmission = super::Transmission { texture, ..super::Transmission::thin(factor) };
    if let Some(volume) = m.extension_value("KHR_materials_volume") {
        transmission.thickness_factor = number(volume, "thicknessFactor", 0.0);
        transmission.thickness_texture = extension_texture(volume, "thicknessTexture", document, named)?;
        transmission.attenuation_distance = number(volume, "attenuationDistance", f32::INFINITY);
        transmission.attenuation_color = color(volume, "attenuationColor", Vec3::ONE, named)?;
    }
    if let Some(dispersion) = m.extension_value("KHR_materials_dispersion") {
        transmission.dispersion = number(dispersion, "dispersion", 0.0);
    }
    Ok(Some(transmission))
}

/// `KHR_texture_transform`'s offset, rotation (radians) and scale, and the `texCoord` it overrides.
type UvTransform = ([f32; 2], f32, [f32; 2], Option<u32>);

/// A texture's use, its coordinates through `transform` where given: the extension's
/// translation · rotation · scale, composed as its GLSL does.
fn texture_ref(texture: &::gltf::Texture, tex_coord: u32, transform: Option<UvTransform>, material: &str) -> Result<TextureRef, String> {
    let (offset, rotation, scale, tex_coord_override) = transform.unwrap_or(([0.0; 2], 0.0, [1.0; 2], None));
    if !(offset.iter().chain(&scale).all(|v| v.is_finite()) && rotation.is_finite()) {
        return Err(format!(
            "{material}: KHR_texture_transform offset {offset:?}, rotation {rotation} and scale {scale:?} must be finite; give finite values"
        ));
    }
    let mut tex_coord = tex_coord_override.unwrap_or(tex_coord);
    if tex_coord > 1 {
        log::warn!("{material}: texture uses TEXCOORD_{tex_coord}; only TEXCOORD_0 and TEXCOORD_1 are read, using TEXCOORD_0");
        tex_coord = 0;
    }
    let (sin, cos) = rotation.sin_cos();
    let linear = Mat2::from_cols(Vec2::new(cos, sin), Vec2::new(-sin, cos)) * Mat2::from_diagonal(Vec2::from(scale));
    let wrap = |mode| match mode {
        ::gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
        ::gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        ::gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
    };
    let sampler = texture.sampler();
    // An image in a format an extension adds is preferred to the core PNG or JPEG fallback.
    let extension_source =
        TEXTURE_SOURCE_EXTENSIONS.iter().find_map(|e| texture.extension_value(e)?.get("source")?.as_u64()).map(|i| i as usize);
    let source = extension_source.or(texture.source().map(|s| s.index())).ok_or_else(|| {
        format!("{material}: texture {} has no image manylights reads (PNG, JPEG, WebP or KTX2); give it a source", texture.index())
    })?;
    Ok(TextureRef {
        texture: source,
        wrap_u: wrap(sampler.wrap_s()),
        wrap_v: wrap(sampler.wrap_t()),
        tex_coord,
        uv_transform: Affine2::from_mat2_translation(linear, Vec2::from(offset)),
    })
}

/// A mesh, and for each of its primitives the glTF vertex each of its vertices was made from (flat
/// normals and tangent seams copy vertices), for the attributes read later (skins, morph targets).
fn mesh(
    mesh: &::gltf::Mesh,
    buffers: &[buffer::Data],
    materials: &[Material],
    default_material: usize,
) -> Result<(Mesh, Vec<Vec<u32>>), String> {
    let name = mesh.name().map_or_else(|| format!("mesh {}", mesh.index()), str::to_owned);
    let mut primitives = Vec::new();
    let mut sources = Vec::new();
    for p in mesh.primitives() {
        let at = || format!("mesh {} ({name}) primitive {}", mesh.index(), p.index());
        if !matches!(p.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            log::warn!("{}: {:?} are not rendered, skipped", at(), p.mode());
            continue;
        }
        let material = p.material().index().unwrap_or(default_material);
        let (primitive, source) = primitive(&p, buffers, material, materials.get(material)).map_err(|e| format!("{}: {e}", at()))?;
        primitives.push(primitive);
        sources.push(source);
    }
    Ok((Mesh { name, primitives }, sources))
}

/// Primitive `p` with `material` (index `material_index`; `None` for glTF's default material), whose
/// textures say which sets of coordinates it needs and which one its normal map's tangents follow.
fn primitive(
    p: &::gltf::Primitive,
    buffers: &[buffer::Data],
    material_index: usize,
    material: Option<&Material>,
) -> Result<(Primitive, Vec<u32>), String> {
    for (semantic, name, dimensions, types) in [
        (Semantic::Positions, "POSITION", Dimensions::Vec3, POSITIONS),
        (Semantic::Normals, "NORMAL", Dimensions::Vec3, DIRECTIONS),
        (Semantic::Tangents, "TANGENT", Dimensions::Vec4, DIRECTIONS),
        (Semantic::TexCoords(0), "TEXCOORD_0", Dimensions::Vec2, TEX_COORDS),
        (Semantic::TexCoords(1), "TEXCOORD_1", Dimensions::Vec2, TEX_COORDS),
    ] {
        if let Some(accessor) = p.get(&semantic) {
            check_accessor(&accessor, name, dimensions, types)?;
        }
    }
    if let Some(accessor) = p.indices() {
        check_accessor(&accessor, "the indices", Dimensions::Scalar, INDICES)?;
    }
    let reader = p.reader(|b| buffers.get(b.index()).map(|d| d.0.as_slice()));
    let positions: Vec<[f32; 3]> =
        p.get(&Semantic::Positions).and_then(|a| read_floats(&a, buffers)).ok_or("POSITION is missing or lies outside its buffer")?;
    if positions.iter().flatten().any(|c| !c.is_finite()) {
        return Err("a vertex position is NaN or infinite".into());
    }
    let count = positions.len();
    let normals: Option<Vec<[f32; 3]>> = vertex_attribute(p.get(&Semantic::Normals), "NORMAL", buffers, count)?;
    let uvs: Option<Vec<[f32; 2]>> = vertex_attribute(p.get(&Semantic::TexCoords(0)), "TEXCOORD_0", buffers, count)?;
    let mut uvs1: Option<Vec<[f32; 2]>> = vertex_attribute(p.get(&Semantic::TexCoords(1)), "TEXCOORD_1", buffers, count)?;
    if uvs1.is_none() && material.is_some_and(|m| m.textures().any(|(t, _)| t.tex_coord == 1)) {
        // glTF requires the set a texture names; TEXCOORD_0 is the likeliest intent.
        let instead = if uvs.is_some() { "reading TEXCOORD_0 instead" } else { "and TEXCOORD_0, so its textures read (0, 0)" };
        log::warn!("material {material_index} reads TEXCOORD_1, which this primitive lacks; {instead}");
        uvs1.clone_from(&uvs);
    }
    let file_tangents: Option<Vec<[f32; 4]>> = vertex_attribute(p.get(&Semantic::Tangents), "TANGENT", buffers, count)?;
    let colors = vertex_colors(p.get(&Semantic::Colors(0)), buffers, count)?;
    let indices: Vec<u32> = match reader.read_indices() {
        Some(indices) => indices.into_u32().collect(),
        None if p.indices().is_some() => return Err("the indices lie outside their buffer".into()),
        None => (0..count as u32).collect(),
    };
    if let Some(bad) = indices.iter().find(|&&i| i as usize >= count) {
        return Err(format!("index {bad} out of range ({count} vertices)"));
    }
    let mut indices = triangle_list(p.mode(), indices);
    if !indices.len().is_multiple_of(3) {
        return Err(format!("index count {} is not a multiple of 3", indices.len()));
    }

    // Non-finite coordinates read as 0 rather than spreading NaN through sampling.
    let finite = |uv: [f32; 2]| if uv.iter().all(|c| c.is_finite()) { uv } else { [0.0; 2] };
    let mut vertices: Vec<Vertex> = (0..count)
        .map(|i| {
            let [u, v] = finite(uvs.as_ref().map_or([0.0; 2], |t| t[i]));
            Vertex {
                position: positions[i],
                u,
                // Broken normals get a placeholder rather than spreading NaN through shading.
                normal: normals.as_ref().map_or([0.0; 3], |n| Vec3::from(n[i]).normalize_or(Vec3::Y).to_array()),
                v,
                tangent: file_tangents.as_ref().map_or([0.0; 4], |t| t[i]),
                color: colors.as_ref().map_or(Vertex::WHITE, |c| Vertex::color_from(c[i])),
                uv1: finite(uvs1.as_ref().map_or([0.0; 2], |t| t[i])),
            }
        })
        .collect();
    let mut sources: Vec<u32> = (0..count as u32).collect();
    if normals.is_none() {
        sources = indices.clone();
        (vertices, indices) = flat_shaded(&vertices, &indices);
    }
    // Tangents follow the coordinates of the normal maps they serve (one frame: the surface's map,
    // else the clear coat's).
    let normal_map = material.and_then(|m| m.normal_texture.or(m.clearcoat.and_then(|c| c.normal_texture)));
    let normal_set = normal_map.map_or(0, |t| t.tex_coord);
    let has_normal_set = if normal_set == 1 { uvs1.is_some() } else { uvs.is_some() };
    if file_tangents.is_none() && has_normal_set {
        let copied = tangents::generate(&mut vertices, &mut indices, normal_set);
        sources = copied.iter().map(|&v| sources[v as usize]).collect();
    } else {
        tangents::orthonormalize(&mut vertices);
    }
    Ok((Primitive { vertices, indices, material: material_index }, sources))
}

/// Component types (with `normalized`) the glTF specification allows for each use of an accessor we
/// read, with `KHR_mesh_quantization`'s for vertex attributes; the gltf crate's readers assume them
/// and panic on others, so they are checked first.
const FLOATS: &[(DataType, bool)] = &[(DataType::F32, false)];
const POSITIONS: &[(DataType, bool)] = &[
    (DataType::F32, false),
    (DataType::I8, false),
    (DataType::I8, true),
    (DataType::U8, false),
    (DataType::U8, true),
    (DataType::I16, false),
    (DataType::I16, true),
    (DataType::U16, false),
    (DataType::U16, true),
];
/// Normals and tangents, and their morph offsets.
const DIRECTIONS: &[(DataType, bool)] = &[(DataType::F32, false), (DataType::I8, true), (DataType::I16, true)];
const MORPH_POSITIONS: &[(DataType, bool)] =
    &[(DataType::F32, false), (DataType::I8, false), (DataType::I8, true), (DataType::I16, false), (DataType::I16, true)];
const TEX_COORDS: &[(DataType, bool)] = POSITIONS;
const COLORS: &[(DataType, bool)] = &[(DataType::F32, false), (DataType::U8, true), (DataType::U16, true)];
const INDICES: &[(DataType, bool)] = &[(DataType::U8, false), (DataType::U16, false), (DataType::U32, false)];
const JOINTS: &[(DataType, bool)] = &[(DataType::U8, false), (DataType::U16, false)];
const WEIGHTS: &[(DataType, bool)] = &[(DataType::F32, false), (DataType::U8, true), (DataType::U16, true)];
/// Rotations and morph weights in animations.
const SIGNED_NORMALIZED: &[(DataType, bool)] =
    &[(DataType::F32, false), (DataType::I8, true), (DataType::U8, true), (DataType::I16, true), (DataType::U16, true)];

/// An accessor's elements as floats: normalized integers mapped to 0..1 or −1..1 as glTF defines,
/// other integers taken as they are (`KHR_mesh_quantization`); `None` where it lies outside its
/// buffer. Its component type must have been checked.
fn read_floats<const N: usize>(accessor: &Accessor, buffers: &[buffer::Data]) -> Option<Vec<[f32; N]>>
where
    [f32; N]: Item,
    [i8; N]: Item,
    [u8; N]: Item,
    [i16; N]: Item,
    [u16; N]: Item,
    [u32; N]: Item,
{
    fn read<T: Copy, const N: usize>(accessor: &Accessor, buffers: &[buffer::Data], to_float: impl Fn(T) -> f32) -> Option<Vec<[f32; N]>>
    where
        [T; N]: Item,
    {
        let items = AccessorIter::<[T; N]>::new(accessor.clone(), |b: ::gltf::Buffer| buffers.get(b.index()).map(|d| d.0.as_slice()))?;
        Some(items.map(|item| item.map(&to_float)).collect())
    }
    let normalized = accessor.normalized();
    // Normalized signed integers map their most negative value to −1 too.
    let signed = |c: f32, max: f32| if normalized { (c / max).max(-1.0) } else { c };
    let unsigned = |c: f32, max: f32| if normalized { c / max } else { c };
    match accessor.data_type() {
        DataType::F32 => read::<f32, N>(accessor, buffers, |c| c),
        DataType::I8 => read::<i8, N>(accessor, buffers, |c| signed(f32::from(c), 127.0)),
        DataType::U8 => read::<u8, N>(accessor, buffers, |c| unsigned(f32::from(c), 255.0)),
        DataType::I16 => read::<i16, N>(accessor, buffers, |c| signed(f32::from(c), 32767.0)),
        DataType::U16 => read::<u16, N>(accessor, buffers, |c| unsigned(f32::from(c), 65535.0)),
        DataType::U32 => read::<u32, N>(accessor, buffers, |c| c as f32),
    }
}

fn check_accessor(accessor: &Accessor, name: &str, dimensions: Dimensions, types: &[(DataType, bool)]) -> Result<(), String> {
    let found = (accessor.data_type(), accessor.normalized());
    if accessor.dimensions() == dimensions && types.contains(&found) {
        return Ok(());
    }
    let describe = |(data_type, normalized): (DataType, bool)| format!("{}{data_type:?}", if normalized { "normalized " } else { "" });
    Err(format!(
        "{name} (accessor {}) is {:?} of {}; glTF allows {dimensions:?} of {}",
        accessor.index(),
        accessor.dimensions(),
        describe(found),
        types.iter().map(|&t| describe(t)).collect::<Vec<_>>().join(", ")
    ))
}

/// An optional vertex attribute as floats (`read_floats`), `count` of them.
fn vertex_attribute<const N: usize>(
    accessor: Option<Accessor>,
    name: &str,
    buffers: &[buffer::Data],
    count: usize,
) -> Result<Option<Vec<[f32; N]>>, String>
where
    [f32; N]: Item,
    [i8; N]: Item,
    [u8; N]: Item,
    [i16; N]: Item,
    [u16; N]: Item,
    [u32; N]: Item,
{
    attribute(name, accessor.is_some(), accessor.and_then(|a| read_floats(&a, buffers)).map(Vec::into_iter), count)
}

/// `COLOR_0` as RGBA: RGB colours get an alpha of 1.
fn vertex_colors(accessor: Option<Accessor>, buffers: &[buffer::Data], count: usize) -> Result<Option<Vec<[f32; 4]>>, String> {
    let Some(accessor) = accessor else { return Ok(None) };
    match accessor.dimensions() {
        Dimensions::Vec3 => {
            check_accessor(&accessor, "COLOR_0", Dimensions::Vec3, COLORS)?;
            let rgb: Option<Vec<[f32; 3]>> = vertex_attribute(Some(accessor), "COLOR_0", buffers, count)?;
            Ok(rgb.map(|rgb| rgb.into_iter().map(|[r, g, b]| [r, g, b, 1.0]).collect()))
        }
        Dimensions::Vec4 => {
            check_accessor(&accessor, "COLOR_0", Dimensions::Vec4, COLORS)?;
            vertex_attribute(Some(accessor), "COLOR_0", buffers, count)
        }
        other => Err(format!("COLOR_0 (accessor {}) is {other:?}; glTF allows Vec3 or Vec4", accessor.index())),
    }
}

/// Reads an optional vertex attribute, telling an absent one (`None`) from one that cannot be read.
fn attribute<T>(name: &str, present: bool, read: Option<impl Iterator<Item = T>>, count: usize) -> Result<Option<Vec<T>>, String> {
    match (present, read) {
        (false, _) => Ok(None),
        (true, None) => Err(format!("{name} lies outside its buffer")),
        (true, Some(values)) => {
            let values: Vec<T> = values.collect();
            if values.len() == count {
                Ok(Some(values))
            } else {
                Err(format!("{name} has {} elements, POSITION has {count}", values.len()))
            }
        }
    }
}

/// Strips and fans as triangle lists (counter-clockwise kept: odd strip triangles are swapped).
fn triangle_list(mode: Mode, indices: Vec<u32>) -> Vec<u32> {
    match mode {
        Mode::TriangleStrip => {
            indices.windows(3).enumerate().flat_map(|(i, w)| if i % 2 == 0 { [w[0], w[1], w[2]] } else { [w[1], w[0], w[2]] }).collect()
        }
        Mode::TriangleFan => match indices.split_first() {
            Some((&hub, rim)) => rim.windows(2).flat_map(|w| [hub, w[0], w[1]]).collect(),
            None => Vec::new(),
        },
        _ => indices,
    }
}

/// Gives each triangle its own three vertices with the face normal (glTF: "When normals are not
/// specified, client implementations MUST calculate flat normals").
fn flat_shaded(vertices: &[Vertex], indices: &[u32]) -> (Vec<Vertex>, Vec<u32>) {
    let mut flat = Vec::with_capacity(indices.len());
    for triangle in indices.chunks_exact(3) {
        let corners = [triangle[0], triangle[1], triangle[2]].map(|i| vertices[i as usize]);
        let [a, b, c] = corners.map(|v| Vec3::from(v.position));
        let normal = (b - a).cross(c - a).normalize_or(Vec3::Y).to_array();
        flat.extend(corners.map(|v| Vertex { normal, ..v }));
    }
    let indices = (0..flat.len() as u32).collect();
    (flat, indices)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::test_support::{assets_dir, temp_dir};

    fn load(relative: &str) -> Scene {
        import(&assets_dir().join(relative)).unwrap_or_else(|e| panic!("{e}"))
    }

    fn count_materials(scene: &Scene, pred: impl Fn(&Material) -> bool) -> usize {
        scene.materials.iter().filter(|m| pred(m)).count()
    }

    /// Every tangent is finite, unit length, orthogonal to its normal and has w = ±1.
    fn assert_tangent_frames(scene: &Scene) {
        for mesh in &scene.meshes {
            for v in mesh.primitives.iter().flat_map(|p| &p.vertices) {
                let (n, t) = (Vec3::from(v.normal), Vec4::from(v.tangent));
                let ok =
                    t.is_finite() && (t.truncate().length() - 1.0).abs() < 1e-3 && t.truncate().dot(n).abs() < 1e-3 && t.w.abs() == 1.0;
                assert!(ok, "{}: tangent {t} with normal {n}", mesh.name);
            }
        }
    }

    #[test]
    fn sponza() {
        let scene = load("sponza/Sponza.gltf");
        assert_eq!(scene.drawn_triangle_count(), 262_087);
        assert_eq!(scene.instances.len(), 170);
        assert_eq!(scene.meshes.len(), 44);
        assert_eq!(scene.materials.len(), 24);
        assert_eq!(scene.textures.len(), 49);
        assert_eq!(scene.cameras.len(), 4);
        let masked = |m: &Material| matches!(m.alpha_mode, AlphaMode::Mask { cutoff } if cutoff == 0.5);
        assert_eq!(count_materials(&scene, masked), 3);
        assert!(scene.textures.iter().all(|t| t.rgba8.len() == (t.width * t.height * 4) as usize));
        assert_tangent_frames(&scene);
    }

    #[test]
    fn gas_station() {
        let scene = load("gas_station/GasStation.gltf");
        assert_eq!(scene.drawn_triangle_count(), 99_002);
        assert_eq!(scene.instances.len(), 1102);
        assert_eq!(scene.meshes.len(), 473);
        assert_eq!(scene.cameras.len(), 2);
        assert_eq!(scene.materials.len(), 95);
        assert_eq!(count_materials(&scene, |m| m.alpha_mode == AlphaMode::Blend), 2);
        assert_tangent_frames(&scene);
        // Its animation poses parts of the station: eleven rotation channels of one keyframe each, so
        // the pose holds at every time.
        let animation = scene.animation.as_ref().expect("the gas station's animation");
        assert_eq!(animation.channels.len(), 11);
        assert!(animation.channels.iter().all(|c| c.property == animation::Property::Rotation && c.times.len() == 1));
        assert!(!animation.instances.is_empty());
        let (now, later) = (animation.instance_transforms(0.0), animation.instance_transforms(5.0));
        assert!(now.iter().zip(&later).all(|(a, b)| a.0 == b.0 && a.1.abs_diff_eq(b.1, 1e-6) && a.1.is_finite()));
    }

    #[test]
    fn damaged_helmet() {
        let scene = load("damaged_helmet/DamagedHelmet.glb");
        assert_eq!(scene.drawn_triangle_count(), 15_452);
        assert_eq!(scene.textures.len(), 5);
        let helmet = &scene.materials[0];
        assert!(helmet.normal_texture.is_some() && helmet.emissive_texture.is_some());
        // Its own texture (image 3), at full strength.
        assert_eq!((helmet.occlusion_texture.map(|t| t.texture), helmet.occlusion_strength), (Some(3), 1.0));
        assert_tangent_frames(&scene);
    }

    #[test]
    fn duck_camera_loses_its_parents_scale() {
        let scene = load("duck/Duck.glb");
        assert_eq!(scene.drawn_triangle_count(), 4_212);
        assert_eq!(scene.textures.len(), 1);
        assert_eq!(scene.cameras.len(), 1);
        // The camera node sits under a node scaled by 0.01.
        let camera = &scene.cameras[0];
        assert!(camera.position().abs_diff_eq(Vec3::new(4.00113, 4.63264, -4.31078), 1e-4), "{}", camera.position());
        let (scale, _, _) = camera.world_from_view.to_scale_rotation_translation();
        assert!(scale.abs_diff_eq(Vec3::ONE, 1e-5), "{scale}");
        assert!(matches!(camera.projection, Projection::Perspective { zfar: Some(zfar), .. } if zfar == 10_000.0));
    }

    #[test]
    fn boxes() {
        for file in ["box/Box.glb", "box/Box.gltf"] {
            let scene = load(file);
            assert_eq!(scene.drawn_triangle_count(), 12, "{file}");
            assert!(scene.textures.is_empty());
            assert_tangent_frames(&scene);
        }
        let textured = load("box_textured/BoxTextured.glb");
        assert_eq!(textured.drawn_triangle_count(), 12);
        assert_eq!(textured.textures.len(), 1);
        let logo = &textured.textures[0];
        // A 211 × 211 palette PNG, expanded to RGBA.
        assert_eq!((logo.width, logo.height, logo.rgba8.len()), (211, 211, 211 * 211 * 4));
        let base = textured.materials[0].base_color_texture.unwrap();
        assert_eq!((base.texture, base.wrap_u, base.wrap_v), (0, Wrap::Repeat, Wrap::Repeat));
    }

    #[test]
    fn missing_file_is_an_io_error() {
        let dir = temp_dir("gltf_missing");
        let result = import(&dir.join("missing.glb"));
        assert!(matches!(result, Err(Error::Io { .. })), "{result:?}");
    }

    #[test]
    fn truncated_file_is_a_gltf_error() {
        let bytes = std::fs::read(assets_dir().join("box/Box.glb")).unwrap();
        let dir = temp_dir("gltf_truncated");
        let path = dir.join("Box.glb");
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        match import(&path) {
            Err(Error::Gltf { path: p, reason }) => {
                assert!(p == path && reason.contains("truncated"), "{reason}")
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn empty_files_and_glbs_without_their_magic_are_named() {
        let dir = temp_dir("gltf_empty");
        for (file, bytes, words) in [
            ("empty.glb", &b""[..], "the file is empty"),
            ("empty.gltf", &b""[..], "the file is empty"),
            ("json.glb", &br#"{"asset": {"version": "2.0"}}"#[..], "starts with the bytes `glTF`"),
        ] {
            std::fs::write(dir.join(file), bytes).unwrap();
            let result = import(&dir.join(file));
            assert!(matches!(&result, Err(Error::Gltf { reason, .. }) if reason.contains(words)), "{file}: {result:?}");
        }
    }

    /// A scene without `nodes` and animation channels that target no node (`KHR_animation_pointer`)
    /// are valid glTF the gltf crate's types refuse: the file loads, in a .gltf and in a GLB.
    #[test]
    fn scenes_without_nodes_and_pointer_channels_load() {
        let dir = temp_dir("gltf_optional_members");
        write_quad_buffer(&dir);
        let quad = std::fs::read(dir.join("quad.bin")).unwrap();
        let json = |uri: &str| {
            format!(
                r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["KHR_animation_pointer"],
                "buffers": [{{{uri}"byteLength": 56}}],
                "bufferViews": [{{"buffer": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 8}}],
                "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
                              {{"bufferView": 1, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]}}],
                "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "mode": 5}}]}}],
                "nodes": [{{"mesh": 0}}],
                "animations": [{{"samplers": [{{"input": 1, "output": 1}}],
                    "channels": [{{"sampler": 0, "target": {{"path": "pointer",
                        "extensions": {{"KHR_animation_pointer": {{"pointer": "/materials/0/alphaCutoff"}}}}}}}}]}}],
                "scenes": [{{"name": "empty"}}, {{"nodes": [0]}}], "scene": 1}}"#
            )
        };
        let gltf = dir.join("optional.gltf");
        std::fs::write(&gltf, json(r#""uri": "quad.bin", "#)).unwrap();
        let mut chunk = json("").into_bytes();
        chunk.resize(chunk.len().next_multiple_of(4), b' ');
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(((28 + chunk.len() + quad.len()) as u32).to_le_bytes());
        glb.extend((chunk.len() as u32).to_le_bytes());
        glb.extend(b"JSON");
        glb.extend(&chunk);
        glb.extend((quad.len() as u32).to_le_bytes());
        glb.extend(b"BIN\0");
        glb.extend(&quad);
        let glb_path = dir.join("optional.glb");
        std::fs::write(&glb_path, glb).unwrap();
        for path in [gltf, glb_path] {
            let scene = import(&path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!((scene.instances.len(), scene.drawn_triangle_count()), (1, 2), "{}", path.display());
        }
    }

    #[test]
    fn unsupported_required_extension_is_named() {
        let dir = temp_dir("gltf_required");
        let path = dir.join("required.gltf");
        let json = r#"{"asset": {"version": "2.0"},
            "extensionsUsed": ["KHR_materials_diffuse_transmission"],
            "extensionsRequired": ["KHR_materials_diffuse_transmission"]}"#;
        std::fs::write(&path, json).unwrap();
        match import(&path) {
            Err(Error::UnsupportedGltfExtension { extension, .. }) => {
                assert_eq!(extension, "KHR_materials_diffuse_transmission")
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn node_cycles_are_errors() {
        let dir = temp_dir("gltf_cycle");
        let path = dir.join("cycle.gltf");
        let json = r#"{"asset": {"version": "2.0"},
            "nodes": [{"children": [1]}, {"children": [0]}], "scenes": [{"nodes": [0]}]}"#;
        std::fs::write(&path, json).unwrap();
        let result = import(&path);
        assert!(matches!(&result, Err(Error::Gltf { reason, .. }) if reason.contains("cycle")), "{result:?}");
        // Forty nodes each listing the next twice: 2⁴⁰ placements if shared children were walked.
        let nodes: Vec<String> = (0..40).map(|i| format!("{{\"children\": [{}, {}]}}", i + 1, i + 1)).chain(["{}".into()]).collect();
        let json = format!(r#"{{"asset": {{"version": "2.0"}}, "nodes": [{}], "scenes": [{{"nodes": [0]}}]}}"#, nodes.join(", "));
        std::fs::write(&path, json).unwrap();
        let result = import(&path);
        assert!(matches!(&result, Err(Error::Gltf { reason, .. }) if reason.contains("node 40 is reached twice")), "{result:?}");
    }

    #[test]
    fn accessors_and_images_that_would_exhaust_memory_are_refused() {
        let dir = temp_dir("gltf_huge");
        let path = dir.join("huge.gltf");
        // Two billion positions from a sparse accessor with no buffer view: 16 bytes in the file.
        let json = r#"{"asset": {"version": "2.0"},
            "buffers": [{"uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAAAAAA==", "byteLength": 16}],
            "bufferViews": [{"buffer": 0, "byteLength": 4}, {"buffer": 0, "byteOffset": 4, "byteLength": 12}],
            "accessors": [{"componentType": 5126, "type": "VEC3", "count": 2000000000, "min": [0, 0, 0], "max": [0, 0, 0],
                "sparse": {"count": 1, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 1}}}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]}"#;
        std::fs::write(&path, json).unwrap();
        let result = import(&path);
        assert!(matches!(&result, Err(Error::Gltf { reason, .. }) if reason.contains("over the 4.0 GiB one scene may hold")), "{result:?}");
        let zero_sparse = json.replace(r#""sparse": {"count": 1"#, r#""sparse": {"count": 0"#);
        std::fs::write(&path, zero_sparse).unwrap();
        let result = import(&path);
        assert!(matches!(&result, Err(Error::Gltf { reason, .. }) if reason.contains("sparse count 0")), "{result:?}");
        // A small JPEG whose header claims 30000 × 30000 pixels is refused before it is decoded.
        let mut jpeg = Vec::new();
        image::RgbImage::new(8, 8).write_to(&mut std::io::Cursor::new(&mut jpeg), image::ImageFormat::Jpeg).unwrap();
        let sof = jpeg.windows(2).position(|w| w == [0xFF, 0xC0]).expect("a baseline JPEG's frame header");
        jpeg[sof + 5..sof + 9].copy_from_slice(&[0x75, 0x30, 0x75, 0x30]);
        let e = decode_limited(&jpeg, image::ImageFormat::Jpeg, &LoadBudget::new()).unwrap_err();
        assert!(e.contains("too large to decode"), "{e}");
    }

    /// `KHR_texture_transform` on a texture info and on a normal texture (which the gltf crate leaves
    /// unparsed) becomes each texture's coordinate transform: translation · rotation · scale, the
    /// rotation as the extension's GLSL writes it.
    #[test]
    fn texture_transforms_become_coordinate_transforms() {
        let mut png = Vec::new();
        image::RgbaImage::new(1, 1).write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).unwrap();
        let dir = temp_dir("gltf_texture_transform");
        let path = dir.join("transformed.gltf");
        let transform = r#"{"KHR_texture_transform": {"offset": [0.5, 0], "rotation": 1.5707964, "scale": [2, 1]}}"#;
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["KHR_texture_transform"],
            "images": [{{"uri": "data:image/png;base64,{}"}}], "textures": [{{"source": 0}}],
            "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0, "extensions": {transform}}},
                "metallicRoughnessTexture": {{"index": 0}}}},
                "normalTexture": {{"index": 0, "extensions": {transform}}}}}]}}"#,
            ::base64::encode(&png)
        );
        std::fs::write(&path, json).unwrap();
        let scene = import(&path).unwrap();
        let material = &scene.materials[0];
        for texture in [material.base_color_texture, material.normal_texture] {
            let t = texture.unwrap().uv_transform;
            assert!(t.transform_point2(Vec2::X).abs_diff_eq(Vec2::new(0.5, 2.0), 1e-6), "{t:?}");
            assert!(t.transform_point2(Vec2::Y).abs_diff_eq(Vec2::new(-0.5, 0.0), 1e-6), "{t:?}");
        }
        assert_eq!(material.metallic_roughness_texture.unwrap().uv_transform, Affine2::IDENTITY);
    }

    /// `KHR_materials_pbrSpecularGlossiness` reads as metallic-roughness with the specular colour as
    /// F0: a textured material gets a roughness image of 1 − glossiness, an untextured one the factor.
    #[test]
    fn specular_glossiness_materials_read_as_metallic_roughness() {
        let mut png = Vec::new();
        image::RgbaImage::from_raw(2, 1, vec![200, 100, 50, 0, 10, 20, 30, 255])
            .unwrap()
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let dir = temp_dir("gltf_specular_glossiness");
        let path = dir.join("specular_glossiness.gltf");
        let textured = r#"{"diffuseFactor": [0.5, 0.6, 0.7, 0.8], "diffuseTexture": {"index": 0}, "specularFactor": [0.2, 0.3, 0.4],
            "glossinessFactor": 0.5, "specularGlossinessTexture": {"index": 0}}"#;
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["{SPECULAR_GLOSSINESS}"],
            "images": [{{"uri": "data:image/png;base64,{}"}}], "textures": [{{"source": 0}}],
            "materials": [{{"extensions": {{"{SPECULAR_GLOSSINESS}": {textured}}}}},
                          {{"extensions": {{"{SPECULAR_GLOSSINESS}": {{"glossinessFactor": 0.25}}}}}}]}}"#,
            ::base64::encode(&png)
        );
        std::fs::write(&path, json).unwrap();
        let scene = import(&path).unwrap();
        let [textured, plain] = &scene.materials[..] else { panic!("two materials") };
        assert_eq!((textured.base_color_factor, textured.base_color_texture.map(|t| t.texture)), (Vec4::new(0.5, 0.6, 0.7, 0.8), Some(0)));
        assert_eq!((textured.metallic_factor, textured.roughness_factor), (0.0, 1.0));
        let specular = textured.specular;
        assert_eq!((specular.ior, specular.factor, specular.color_factor), (0.0, 1.0, Vec3::new(0.2, 0.3, 0.4)));
        assert_eq!(specular.color_texture.map(|t| t.texture), Some(0), "the specular colour is the texture's RGB");
        let roughness = &scene.textures[textured.metallic_roughness_texture.unwrap().texture];
        // G = 1 − 0.5 × alpha: 1 where the texel is matt (alpha 0), 0.5 where it is glossy.
        assert_eq!(roughness.rgba8, vec![0, 255, 0, 255, 0, 128, 0, 255]);
        assert_eq!((plain.base_color_factor, plain.roughness_factor, plain.metallic_roughness_texture), (Vec4::ONE, 0.75, None));
        assert_eq!(scene.textures.len(), 2, "one roughness image made");
    }

    #[test]
    fn punctual_lights_and_material_extensions() {
        let dir = temp_dir("gltf_lights");
        let path = dir.join("lights.gltf");
        let json = r#"{
            "asset": {"version": "2.0"},
            "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
            "extensionsRequired": ["KHR_lights_punctual"],
            "extensions": {"KHR_lights_punctual": {"lights": [
                {"type": "point", "color": [1, 0.5, 0.25], "intensity": 20},
                {"type": "spot", "intensity": 50, "range": 8,
                 "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}},
                {"type": "directional", "color": [1, 0.9, 0.8], "intensity": 3},
                {"type": "directional", "intensity": 1}
            ]}},
            "materials": [{"emissiveFactor": [1, 0.5, 0], "alphaMode": "MASK",
                "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}}}],
            "nodes": [
                {"translation": [1, 0, 0], "children": [1]},
                {"translation": [0, 2, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
                {"translation": [0, 4, 0], "rotation": [-0.7071068, 0, 0, 0.7071068],
                 "extensions": {"KHR_lights_punctual": {"light": 1}}},
                {"rotation": [-0.7071068, 0, 0, 0.7071068], "extensions": {"KHR_lights_punctual": {"light": 2}}},
                {"extensions": {"KHR_lights_punctual": {"light": 3}}}
            ],
            "scenes": [{"nodes": [0, 2, 3, 4]}]
        }"#;
        std::fs::write(&path, json).unwrap();
        let scene = import(&path).unwrap();

        assert_eq!(scene.lights.len(), 2);
        let point = scene.lights[0];
        assert_eq!(point.kind, LightKind::Point);
        assert!(point.position.abs_diff_eq(Vec3::new(1.0, 2.0, 0.0), 1e-6));
        assert_eq!(point.color, Vec3::new(1.0, 0.5, 0.25));
        // No range in the file: where 20 cd / d² falls to the cutoff.
        assert!((point.range - (20.0f32 / DEFAULT_LIGHT_CUTOFF).sqrt()).abs() < 1e-3, "{}", point.range);

        let spot = scene.lights[1];
        assert_eq!(spot.kind, LightKind::Spot { inner_cone_angle: 0.2, outer_cone_angle: 0.5 });
        assert!(spot.position.abs_diff_eq(Vec3::new(0.0, 4.0, 0.0), 1e-6));
        assert!(spot.direction.abs_diff_eq(Vec3::NEG_Y, 1e-5), "{}", spot.direction);
        assert_eq!((spot.intensity, spot.range), (50.0, 8.0));

        let sun = scene.sun.unwrap();
        assert!(sun.direction.abs_diff_eq(Vec3::NEG_Y, 1e-5));
        assert_eq!((sun.color, sun.illuminance), (Vec3::new(1.0, 0.9, 0.8), 3.0));

        let material = &scene.materials[0];
        assert_eq!(material.emissive_factor, Vec3::new(4.0, 2.0, 0.0));
        assert_eq!(material.alpha_mode, AlphaMode::Mask { cutoff: 0.5 });
    }

    /// Writes a quad's four corners (no normals, no UVs) and one index list as `quad.bin`.
    fn write_quad_buffer(dir: &Path) {
        let positions = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        let mut bytes: Vec<u8> = positions.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
        bytes.extend([0u16, 1, 3, 2].iter().flat_map(|i| i.to_le_bytes()));
        std::fs::write(dir.join("quad.bin"), bytes).unwrap();
    }

    #[test]
    fn strips_fans_points_flat_normals_default_material_and_instancing() {
        let dir = temp_dir("gltf_modes");
        write_quad_buffer(&dir);
        let json = r#"{
            "asset": {"version": "2.0"},
            "buffers": [{"uri": "quad.bin", "byteLength": 56}],
            "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 8}],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5123, "count": 4, "type": "SCALAR"}
            ],
            "meshes": [{"primitives": [
                {"attributes": {"POSITION": 0}, "mode": 5},
                {"attributes": {"POSITION": 0}, "indices": 1, "mode": 6},
                {"attributes": {"POSITION": 0}, "mode": 0}
            ]}],
            "nodes": [
                {"mesh": 0, "translation": [1, 0, 0], "children": [1]},
                {"mesh": 0, "translation": [0, 0, 2], "scale": [2, 2, 2]}
            ],
            "scenes": [{"nodes": [0]}]
        }"#;
        std::fs::write(dir.join("modes.gltf"), json).unwrap();
        let scene = import(&dir.join("modes.gltf")).unwrap();

        assert_eq!(scene.meshes.len(), 1);
        let primitives = &scene.meshes[0].primitives;
        assert_eq!(primitives.len(), 2, "the points primitive is skipped");
        for p in primitives {
            assert_eq!(p.triangle_count(), 2);
            // Flat normals unweld the vertices; both triangles face +Z (counter-clockwise kept).
            assert_eq!(p.vertices.len(), 6);
            assert!(p.vertices.iter().all(|v| v.normal == [0.0, 0.0, 1.0]));
            assert_eq!(p.material, 0);
        }
        assert_eq!(scene.materials.len(), 1, "the default material is appended");
        assert_eq!(scene.materials[0].name, "default");
        assert_tangent_frames(&scene);

        assert_eq!(scene.instances.len(), 2);
        assert!(scene.instances.iter().all(|i| i.mesh == 0));
        let origin = |i: usize| scene.instances[i].world_from_local.transform_point3(Vec3::ZERO);
        assert_eq!((origin(0), origin(1)), (Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 2.0)));
        assert_eq!(scene.drawn_triangle_count(), 8);
    }

    /// The quad of `write_quad_buffer` with `accessors` (its positions first) replacing the file's,
    /// `primitive` its mesh's primitive and `extra` more top-level members; the import's result.
    fn import_quad(name: &str, accessors: &str, primitive: &str, extra: &str) -> Result<Scene> {
        let dir = temp_dir(name);
        write_quad_buffer(&dir);
        let json = format!(
            r#"{{
            "asset": {{"version": "2.0"}},
            "buffers": [{{"uri": "quad.bin", "byteLength": 56}}],
            "bufferViews": [{{"buffer": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 8}}],
            "accessors": [{accessors}],
            "meshes": [{{"primitives": [{primitive}]}}],
            "nodes": [{{"mesh": 0}}],
            "scenes": [{{"nodes": [0]}}]{extra}
        }}"#
        );
        std::fs::write(dir.join("quad.gltf"), json).unwrap();
        import(&dir.join("quad.gltf"))
    }

    /// A single-level 2D KTX2 file of `vk_format` holding `level` (supercompressed by `scheme`).
    fn ktx2_file(vk_format: u32, (width, height): (u32, u32), scheme: u32, level: &[u8], uncompressed: usize) -> Vec<u8> {
        let mut file = KTX2_MAGIC.to_vec();
        for word in [vk_format, 1, width, height, 0, 0, 1, 1, scheme] {
            file.extend(word.to_le_bytes());
        }
        // The data format descriptor (only its length word) at 104, no key-value or global data.
        for word in [104u32, 4, 0, 0] {
            file.extend(word.to_le_bytes());
        }
        file.extend([0u8; 16]);
        for word in [108u64, level.len() as u64, uncompressed as u64] {
            file.extend(word.to_le_bytes());
        }
        file.extend(4u32.to_le_bytes());
        file.extend(level);
        file
    }

    #[test]
    fn plain_ktx2_textures_expand_to_rgba8_stored_or_in_zstandard() {
        const R8G8B8_SRGB: u32 = 29;
        let texels: Vec<u8> = (0..12).map(|i| i * 20).collect();
        let expected: Vec<u8> = texels.chunks(3).flat_map(|t| [t[0], t[1], t[2], 255]).collect();
        let budget = LoadBudget::new();
        let stored = ktx2_file(R8G8B8_SRGB, (2, 2), 0, &texels, texels.len());
        assert_eq!(decode_ktx2(&stored, &budget), Ok((2, 2, expected.clone())));
        // A Zstandard frame of one raw block: magic, a single-segment header with a one-byte
        // content size, the last block's header (raw, 12 bytes).
        let mut zstd = vec![0x28, 0xB5, 0x2F, 0xFD, 0x20, texels.len() as u8];
        zstd.extend(&(1u32 | (texels.len() as u32) << 3).to_le_bytes()[..3]);
        zstd.extend(&texels);
        let compressed = ktx2_file(R8G8B8_SRGB, (2, 2), 2, &zstd, texels.len());
        assert_eq!(decode_ktx2(&compressed, &budget), Ok((2, 2, expected)));
        // One channel: red, as a sampler reads it.
        let red = ktx2_file(9, (2, 1), 0, &[7, 9], 2);
        assert_eq!(decode_ktx2(&red, &budget), Ok((2, 1, vec![7, 0, 0, 255, 9, 0, 0, 255])));

        let half_floats = ktx2_file(97, (1, 1), 0, &[0; 8], 8);
        let error = decode_ktx2(&half_floats, &budget).unwrap_err();
        assert!(error.contains("R16G16B16A16_SFLOAT") && error.contains("give a PNG"), "{error}");
        let short = ktx2_file(R8G8B8_SRGB, (2, 2), 0, &texels[..9], 9);
        assert!(decode_ktx2(&short, &budget).unwrap_err().contains("holds 9 bytes where 2×2"));
    }

    #[test]
    fn accessors_without_data_read_as_zeros() {
        let positions = r#"{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}"#;
        let colors = r#"{"componentType": 5126, "count": 4, "type": "VEC4"}"#;
        let scene = import_quad(
            "gltf_zero_accessor",
            &format!("{positions}, {colors}"),
            r#"{"attributes": {"POSITION": 0, "COLOR_0": 1}, "mode": 5}"#,
            "",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let vertices = &scene.meshes[0].primitives[0].vertices;
        assert!(!vertices.is_empty() && vertices.iter().all(|v| v.color == [0; 4]), "{:?}", vertices[0].color);
    }

    #[test]
    fn quantized_attributes_read_as_the_extension_says() {
        // Positions as plain (not normalized) 16-bit integers, negative ones included; texture
        // coordinates as normalized 8-bit ones.
        let positions: [[i16; 3]; 3] = [[-300, 0, 7], [200, -1, 0], [0, 500, -32768]];
        let mut bytes: Vec<u8> = positions.iter().flat_map(|p| [p[0], p[1], p[2], 0]).flat_map(i16::to_le_bytes).collect();
        bytes.extend([0u8, 255, 255, 0, 128, 64, 0, 0]);
        let data = ::base64::encode(&bytes);
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["KHR_mesh_quantization"], "extensionsRequired": ["KHR_mesh_quantization"],
            "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}"}}],
            "bufferViews": [{{"buffer": 0, "byteLength": 24, "byteStride": 8}}, {{"buffer": 0, "byteOffset": 24, "byteLength": 6}}],
            "accessors": [{{"bufferView": 0, "componentType": 5122, "count": 3, "type": "VEC3", "min": [-300, -1, -32768], "max": [200, 500, 7]}},
                          {{"bufferView": 1, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC2"}}],
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}}}]}}],
            "nodes": [{{"mesh": 0}}], "scenes": [{{"nodes": [0]}}]}}"#,
            len = bytes.len()
        );
        let dir = temp_dir("gltf_quantized");
        let path = dir.join("quantized.gltf");
        std::fs::write(&path, json).unwrap();
        let scene = import(&path).unwrap();
        // Flat shading gives each corner its own vertex, in order.
        let vertices = &scene.meshes[0].primitives[0].vertices;
        let read: Vec<[f32; 3]> = vertices.iter().map(|v| v.position).collect();
        assert_eq!(read, positions.map(|p| p.map(f32::from)).to_vec());
        let uvs: Vec<[f32; 2]> = vertices.iter().map(|v| [v.u, v.v]).collect();
        assert_eq!(uvs, vec![[0.0, 1.0], [1.0, 0.0], [128.0 / 255.0, 64.0 / 255.0]]);
    }

    #[test]
    fn accessors_of_types_the_specification_forbids_are_errors() {
        let positions = r#"{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}"#;
        let strip = r#"{"attributes": {"POSITION": 0}, "mode": 5}"#;
        let indexed = r#"{"attributes": {"POSITION": 0}, "indices": 1}"#;
        let translation_of = |node: u32| {
            format!(
                r#", "animations": [{{"channels": [{{"sampler": 0, "target": {{"node": {node}, "path": "translation"}}}}],
                "samplers": [{{"input": 1, "output": 0}}]}}]"#
            )
        };
        // (test, accessors, primitive, more members, words the error must hold)
        let cases = [
            // Float indices: the gltf crate's reader would reach `unreachable!()`.
            (
                "gltf_float_indices",
                format!(r#"{positions}, {{"bufferView": 1, "componentType": 5126, "count": 2, "type": "SCALAR"}}"#),
                indexed,
                String::new(),
                &["the indices (accessor 1)", "F32", "U32"][..],
            ),
            (
                "gltf_vector_indices",
                format!(r#"{positions}, {{"bufferView": 1, "componentType": 5123, "count": 1, "type": "VEC3"}}"#),
                indexed,
                String::new(),
                &["the indices (accessor 1) is Vec3"],
            ),
            (
                "gltf_uint_uvs",
                format!(r#"{positions}, {{"bufferView": 0, "componentType": 5125, "count": 4, "type": "VEC2"}}"#),
                r#"{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}}"#,
                String::new(),
                &["TEXCOORD_0 (accessor 1) is Vec2 of U32", "normalized U16"],
            ),
            // KHR_mesh_quantization allows 8- and 16-bit positions, never 32-bit integers.
            (
                "gltf_uint_positions",
                r#"{"bufferView": 0, "componentType": 5125, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}"#.to_owned(),
                strip,
                String::new(),
                &["POSITION (accessor 0) is Vec3 of U32", "normalized U16"],
            ),
            // Keyframe times must be floats.
            (
                "gltf_integer_times",
                format!(r#"{positions}, {{"bufferView": 1, "componentType": 5123, "count": 4, "type": "SCALAR"}}"#),
                strip,
                translation_of(0),
                &["channel 0 keyframe times (accessor 1) is Scalar of U16"],
            ),
            // A channel animating a node the file lacks: the gltf crate's `target().node()` would panic.
            (
                "gltf_channel_node",
                format!(r#"{positions}, {{"bufferView": 1, "componentType": 5126, "count": 2, "type": "SCALAR"}}"#),
                strip,
                translation_of(99),
                &["animation 0 channel 0: target node 99 does not exist"],
            ),
        ];
        for (test, accessors, primitive, extra, words) in cases {
            match import_quad(test, &accessors, primitive, &extra) {
                Err(Error::Gltf { reason, .. }) => assert!(words.iter().all(|w| reason.contains(w)), "{test}: {reason}"),
                other => panic!("{test}: {other:?}"),
            }
        }
        // The quad alone loads.
        assert!(import_quad("gltf_quad_ok", positions, strip, "").is_ok());
    }

    #[test]
    fn other_major_versions_and_degenerate_cameras_are_errors() {
        let dir = temp_dir("gltf_version");
        std::fs::write(dir.join("v3.gltf"), r#"{"asset": {"version": "3.0"}}"#).unwrap();
        let result = import(&dir.join("v3.gltf"));
        assert!(matches!(&result, Err(Error::Gltf { reason, .. }) if reason.contains("\"3.0\"") && reason.contains("2.x")), "{result:?}");

        let positions = r#"{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}"#;
        let with_camera = |name: &str, camera: &str| {
            let extra = format!(r#", "cameras": [{camera}]"#);
            let dir = temp_dir(name);
            write_quad_buffer(&dir);
            let json = format!(
                r#"{{"asset": {{"version": "2.0"}}, "buffers": [{{"uri": "quad.bin", "byteLength": 56}}],
                "bufferViews": [{{"buffer": 0, "byteLength": 48}}], "accessors": [{positions}],
                "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "mode": 5}}]}}],
                "nodes": [{{"mesh": 0}}, {{"camera": 0, "translation": [0, 0, 5]}}], "scenes": [{{"nodes": [0, 1]}}]{extra}}}"#
            );
            std::fs::write(dir.join("camera.gltf"), json).unwrap();
            import(&dir.join("camera.gltf"))
        };
        for (name, camera, words) in [
            ("gltf_yfov0", r#"{"type": "perspective", "perspective": {"yfov": 0, "znear": 0.1}}"#, "yfov 0"),
            ("gltf_znear_negative", r#"{"type": "perspective", "perspective": {"yfov": 0.8, "znear": -1}}"#, "znear -1"),
            ("gltf_zfar_near", r#"{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 1, "zfar": 0.5}}"#, "zfar 0.5"),
            // Valid JSON numbers the GPU would flush to zero: nothing would be drawn.
            (
                "gltf_znear_denormal",
                r#"{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 1e-38}}"#,
                "znear 0.00000000000000000000000000000000000001",
            ),
            (
                "gltf_ortho0",
                r#"{"type": "orthographic", "orthographic": {"xmag": 0, "ymag": 0, "znear": 1, "zfar": 1}}"#,
                "xmag 0 and ymag 0",
            ),
        ] {
            let result = with_camera(name, camera);
            assert!(
                matches!(&result, Err(Error::Gltf { reason, .. }) if reason.contains("camera 0") && reason.contains(words)),
                "{name}: {result:?}"
            );
        }
        let fine = with_camera("gltf_camera_ok", r#"{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 100}}"#);
        assert_eq!(fine.unwrap().cameras.len(), 1);
    }

    #[test]
    fn buffer_views_outside_their_buffer_are_errors() {
        let dir = temp_dir("gltf_view_bounds");
        write_quad_buffer(&dir);
        let json = r#"{
            "asset": {"version": "2.0"},
            "buffers": [{"uri": "quad.bin", "byteLength": 56}],
            "bufferViews": [{"buffer": 0, "byteOffset": 40, "byteLength": 48}]
        }"#;
        std::fs::write(dir.join("bounds.gltf"), json).unwrap();
        let result = import(&dir.join("bounds.gltf"));
        assert!(matches!(&result, Err(Error::Gltf { reason, .. }) if reason.contains("outside buffer 0")), "{result:?}");
    }

    #[test]
    fn uris_that_would_panic_the_loader_are_errors() {
        assert_eq!(percent_decode("a%20b%C3%A9.png").as_deref(), Some("a bé.png"));
        assert_eq!(percent_decode("100%.png").as_deref(), Some("100%.png"));
        let dir = temp_dir("gltf_uri");
        let path = dir.join("uri.gltf");
        let json = r#"{"asset": {"version": "2.0"}, "buffers": [{"uri": "%FF.bin", "byteLength": 4}]}"#;
        std::fs::write(&path, json).unwrap();
        let result = import(&path);
        assert!(matches!(&result, Err(Error::Gltf { reason, .. }) if reason.contains("UTF-8")), "{result:?}");
    }

    #[test]
    fn every_pixel_format_expands_to_rgba8() {
        use ::gltf::image::{Data, Format};
        let data = |format, pixels: Vec<u8>| Data { pixels, format, width: 1, height: 1 };
        let u16s = |v: &[u16]| v.iter().flat_map(|c| c.to_ne_bytes()).collect();
        let f32s = |v: &[f32]| v.iter().flat_map(|c| c.to_ne_bytes()).collect();
        let cases = [
            (data(Format::R8, vec![7]), [7, 7, 7, 255]),
            (data(Format::R8G8, vec![7, 9]), [7, 7, 7, 9]),
            (data(Format::R8G8B8, vec![1, 2, 3]), [1, 2, 3, 255]),
            (data(Format::R8G8B8A8, vec![1, 2, 3, 4]), [1, 2, 3, 4]),
            (data(Format::R16, u16s(&[65535])), [255, 255, 255, 255]),
            (data(Format::R16G16, u16s(&[0, 32896])), [0, 0, 0, 128]),
            (data(Format::R16G16B16, u16s(&[257, 514, 65535])), [1, 2, 255, 255]),
            (data(Format::R16G16B16A16, u16s(&[0, 257, 0, 65535])), [0, 1, 0, 255]),
            (data(Format::R32G32B32FLOAT, f32s(&[0.0, 0.5, 2.0])), [0, 128, 255, 255]),
            (data(Format::R32G32B32A32FLOAT, f32s(&[1.0, -1.0, f32::NAN, 0.25])), [255, 0, 0, 64]),
        ];
        for (image, rgba) in cases {
            let format = image.format;
            assert_eq!(to_rgba8(image), rgba, "{format:?}");
        }
    }
}
