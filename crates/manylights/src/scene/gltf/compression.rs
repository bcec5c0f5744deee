//! Compressed glTF geometry, decoded before anything reads the buffers, so the rest of the importer
//! reads plain ones:
//! - `EXT_meshopt_compression`: each compressed buffer view is decoded by meshoptimizer's own decoder
//!   (the `meshopt` crate) into the place the view names, usually in a fallback buffer that has no
//!   data of its own, with the view's filter applied.
//! - `KHR_draco_mesh_compression`: each compressed primitive is decoded (`draco-core`, a pure-Rust
//!   Draco decoder) into a buffer of its own, and its accessors are pointed at the decoded data;
//!   attributes the extension does not name are read as usual, as its specification says.
//! - Accessors with neither a buffer view nor sparse values hold zeros (glTF 2.0, 3.6.2.1), which
//!   the gltf crate would refuse: they are pointed at zeros in the same buffer.

use ::gltf::buffer;
use ::gltf::json::{self, validation::Checked};
use serde_json::Value;

use crate::files::LoadBudget;

pub const MESHOPT: &str = "EXT_meshopt_compression";
pub const DRACO: &str = "KHR_draco_mesh_compression";

/// A buffer that holds no data but what meshopt decodes into it: its length, to allocate.
pub fn fallback_length(buffer: &json::Buffer) -> Option<usize> {
    let fallback = buffer.extensions.as_ref()?.others.get(MESHOPT)?.get("fallback")?.as_bool()?;
    (fallback && buffer.uri.is_none()).then_some(buffer.byte_length.0 as usize)
}

/// A required unsigned integer member of an extension object.
fn member(object: &Value, name: &str, what: &str) -> Result<usize, String> {
    object.get(name).and_then(Value::as_u64).map(|v| v as usize).ok_or_else(|| format!("{what} has no unsigned integer `{name}`"))
}

/// Bytes `offset..offset + length` of buffer `index`.
fn bytes_of(buffers: &[buffer::Data], index: usize, offset: usize, length: usize) -> Option<&[u8]> {
    buffers.get(index)?.0.get(offset..offset.checked_add(length)?)
}

/// Decodes both extensions' data (the file is not validated yet: every index is checked here), and
/// gives accessors with no data of their own the zeros the specification says they hold (the gltf
/// crate refuses them). Decoded data and zeros go to one buffer appended to `buffers`.
pub fn decode(root: &mut json::Root, buffers: &mut Vec<buffer::Data>, budget: &LoadBudget, path: &std::path::Path) -> Result<(), String> {
    decode_meshopt(root, buffers, budget, path)?;
    let mut appended = Vec::new();
    let appended_buffer = buffers.len();
    decode_draco(root, buffers, &mut appended, budget, path)?;
    fill_zero_accessors(root, &mut appended, appended_buffer, budget, path)?;
    if !appended.is_empty() {
        root.buffers.push(json::Buffer {
            byte_length: appended.len().into(),
            name: None,
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        buffers.push(buffer::Data(appended));
    }
    Ok(())
}

/// Points every accessor with neither a buffer view nor sparse values at zeros of its size.
fn fill_zero_accessors(
    root: &mut json::Root,
    appended: &mut Vec<u8>,
    appended_buffer: usize,
    budget: &LoadBudget,
    path: &std::path::Path,
) -> Result<(), String> {
    for index in 0..root.accessors.len() {
        let accessor = &root.accessors[index];
        if accessor.buffer_view.is_some() || accessor.sparse.is_some() {
            continue;
        }
        let (Checked::Valid(kind), Checked::Valid(component)) = (accessor.type_, accessor.component_type) else { continue };
        let bytes = accessor.count.0.saturating_mul(element_size(kind, component.0) as u64);
        budget.take_input(bytes, path).map_err(|e| e.to_string())?;
        let offset = appended.len();
        appended.resize(offset + bytes as usize, 0);
        view_over(&mut root.accessors[index], &mut root.buffer_views, appended, offset, appended_buffer);
    }
    Ok(())
}

/// Bytes an element of `kind` takes in a buffer: matrices' columns start 4-byte aligned (glTF 2.0,
/// 3.6.2.4).
fn element_size(kind: json::accessor::Type, component: json::accessor::ComponentType) -> usize {
    use json::accessor::Type;
    let column = |rows: usize| (rows * component.size()).next_multiple_of(4);
    match kind {
        Type::Mat2 => 2 * column(2),
        Type::Mat3 => 3 * column(3),
        Type::Mat4 => 4 * column(4),
        _ => kind.multiplicity() * component.size(),
    }
}

/// Decodes every meshopt-compressed buffer view into the bytes the view names.
fn decode_meshopt(root: &json::Root, buffers: &mut [buffer::Data], budget: &LoadBudget, path: &std::path::Path) -> Result<(), String> {
    for (index, view) in root.buffer_views.iter().enumerate() {
        let Some(ext) = view.extensions.as_ref().and_then(|e| e.others.get(MESHOPT)) else { continue };
        let what = format!("buffer view {index}'s {MESHOPT}");
        let source_buffer = member(ext, "buffer", &what)?;
        let offset = ext.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
        let length = member(ext, "byteLength", &what)?;
        let stride = member(ext, "byteStride", &what)?;
        let count = member(ext, "count", &what)?;
        let mode = ext.get("mode").and_then(Value::as_str).ok_or_else(|| format!("{what} has no `mode`"))?;
        let filter = ext.get("filter").and_then(Value::as_str).unwrap_or("NONE");
        let view_length = view.byte_length.0 as usize;
        let size = count
            .checked_mul(stride)
            .filter(|&s| s == view_length)
            .ok_or_else(|| format!("{what} decodes {count} elements of {stride} bytes, and its view holds {view_length} bytes"))?;
        budget.take_input(size as u64, path).map_err(|e| e.to_string())?;
        let source = bytes_of(buffers, source_buffer, offset, length)
            .ok_or_else(|| format!("{what}: bytes {offset}..+{length} lie outside buffer {source_buffer}"))?;
        let decoded = decode_view(source, count, stride, mode, filter).map_err(|e| format!("{what}: {e}"))?;
        let (target, target_offset) = (view.buffer.value(), view.byte_offset.map_or(0, |o| o.0 as usize));
        let target = buffers
            .get_mut(target)
            .and_then(|b| b.0.get_mut(target_offset..target_offset.checked_add(size)?))
            .ok_or_else(|| format!("buffer view {index} lies outside buffer {target}"))?;
        target.copy_from_slice(&decoded);
    }
    Ok(())
}

/// One view's `count` elements of `stride` bytes, decoded and filtered.
fn decode_view(source: &[u8], count: usize, stride: usize, mode: &str, filter: &str) -> Result<Vec<u8>, String> {
    let failed = |e: meshopt::Error| format!("the {mode} stream does not decode ({e:?})");
    match mode {
        "ATTRIBUTES" => {
            if stride == 0 || !stride.is_multiple_of(4) || stride > 256 {
                return Err(format!("byteStride {stride} of ATTRIBUTES must be a multiple of 4 up to 256"));
            }
            // Words, so the filters' 16- and 32-bit components are aligned.
            let mut words = vec![0u32; count * stride / 4];
            // SAFETY: `words` holds exactly `count` elements of `stride` bytes, which is all the
            // decoder writes; it reads only `source`.
            let code = unsafe {
                meshopt::ffi::meshopt_decodeVertexBuffer(words.as_mut_ptr().cast(), count, stride, source.as_ptr(), source.len())
            };
            if code != 0 {
                return Err(format!("the ATTRIBUTES stream does not decode (code {code})"));
            }
            let filter_fn = match (filter, stride) {
                ("NONE", _) => None,
                ("OCTAHEDRAL", 4 | 8) => Some(meshopt::ffi::meshopt_decodeFilterOct as unsafe extern "C" fn(_, _, _)),
                ("QUATERNION", 8) => Some(meshopt::ffi::meshopt_decodeFilterQuat as unsafe extern "C" fn(_, _, _)),
                ("EXPONENTIAL", _) => Some(meshopt::ffi::meshopt_decodeFilterExp as unsafe extern "C" fn(_, _, _)),
                _ => return Err(format!("filter {filter} with byteStride {stride} is not one the extension defines")),
            };
            if let Some(filter_fn) = filter_fn {
                // SAFETY: the filter rewrites `count` elements of `stride` bytes in place, a stride
                // it accepts (checked above), all within `words`.
                unsafe { filter_fn(words.as_mut_ptr().cast(), count, stride) };
            }
            Ok(bytemuck::cast_slice(&words).to_vec())
        }
        "TRIANGLES" | "INDICES" => {
            if filter != "NONE" {
                return Err(format!("filter {filter} does not apply to {mode}"));
            }
            // meshoptimizer asserts (aborting the process) on a triangle list that is not one.
            if mode == "TRIANGLES" && !count.is_multiple_of(3) {
                return Err(format!("TRIANGLES has {count} indices, not a multiple of 3"));
            }
            match (mode, stride) {
                ("TRIANGLES", 2) => meshopt::decode_index_buffer::<u16>(source, count).map(|v| bytemuck::cast_slice(&v).to_vec()),
                ("TRIANGLES", 4) => meshopt::decode_index_buffer::<u32>(source, count).map(|v| bytemuck::cast_slice(&v).to_vec()),
                ("INDICES", 2) => meshopt::decode_index_sequence::<u16>(source, count).map(|v| bytemuck::cast_slice(&v).to_vec()),
                ("INDICES", 4) => meshopt::decode_index_sequence::<u32>(source, count).map(|v| bytemuck::cast_slice(&v).to_vec()),
                _ => return Err(format!("byteStride {stride} of {mode} must be 2 or 4")),
            }
            .map_err(failed)
        }
        _ => Err(format!("mode {mode} is not ATTRIBUTES, TRIANGLES or INDICES")),
    }
}

/// Decodes every Draco-compressed primitive into `decoded`, the data of the buffer appended after
/// `buffers`, pointing its accessors at the decoded data (indices as 32-bit integers).
fn decode_draco(
    root: &mut json::Root,
    buffers: &[buffer::Data],
    decoded: &mut Vec<u8>,
    budget: &LoadBudget,
    path: &std::path::Path,
) -> Result<(), String> {
    let decoded_buffer = buffers.len();
    for m in 0..root.meshes.len() {
        for p in 0..root.meshes[m].primitives.len() {
            let primitive = &root.meshes[m].primitives[p];
            let Some(ext) = primitive.extensions.as_ref().and_then(|e| e.others.get(DRACO)).cloned() else { continue };
            let what = format!("mesh {m} primitive {p}'s {DRACO}");
            let view = root.buffer_views.get(member(&ext, "bufferView", &what)?).ok_or_else(|| format!("{what} names no buffer view"))?;
            let bytes = bytes_of(buffers, view.buffer.value(), view.byte_offset.map_or(0, |o| o.0 as usize), view.byte_length.0 as usize)
                .ok_or_else(|| format!("{what}: its buffer view lies outside its buffer"))?;
            let mut draco = draco_core::Mesh::new();
            draco_core::MeshDecoder::new()
                .decode(&mut draco_core::DecoderBuffer::new(bytes), &mut draco)
                .map_err(|e| format!("{what}: the Draco stream does not decode ({e:?})"))?;
            let points = draco.num_points();
            let ids = ext.get("attributes").and_then(Value::as_object).ok_or_else(|| format!("{what} has no `attributes`"))?;
            let accessor_of = |index: usize| {
                (index < root.accessors.len()).then_some(index).ok_or_else(|| format!("{what}: accessor {index} does not exist"))
            };
            let mut writes: Vec<(usize, Vec<u8>, usize, Option<json::accessor::ComponentType>)> = Vec::new();
            if let Some(indices) = primitive.indices {
                let values: Vec<u32> = draco.faces().iter().flat_map(|f| f.map(|v| v.0)).collect();
                writes.push((
                    accessor_of(indices.value())?,
                    bytemuck::cast_slice(&values).to_vec(),
                    values.len(),
                    Some(json::accessor::ComponentType::U32),
                ));
            }
            for (semantic, accessor) in &primitive.attributes {
                let name = match semantic {
                    Checked::Valid(semantic) => semantic.to_string(),
                    Checked::Invalid => return Err(format!("{what}: an attribute has an invalid name")),
                };
                // The extension's specification has loaders read attributes it does not name as usual.
                let Some(id) = ids.get(&name).and_then(Value::as_u64) else { continue };
                let attribute = draco
                    .attribute_by_unique_id(id as u32)
                    .ok_or_else(|| format!("{what}: {name}'s Draco attribute {id} is not in the stream"))?;
                let index = accessor_of(accessor.value())?;
                let json_accessor = &root.accessors[index];
                let (Checked::Valid(kind), Checked::Valid(component)) = (json_accessor.type_, json_accessor.component_type) else {
                    return Err(format!("{what}: accessor {index} has an invalid type"));
                };
                let values = attribute.read_f32s(points, kind.multiplicity());
                writes.push((index, encode_as(&values, component.0), points, None));
            }
            for (index, bytes, count, component) in writes {
                budget.take_input(bytes.len() as u64, path).map_err(|e| e.to_string())?;
                let accessor = &mut root.accessors[index];
                if let Some(component) = component {
                    accessor.component_type = Checked::Valid(json::accessor::GenericComponentType(component));
                }
                accessor.count = count.into();
                point_at(accessor, &mut root.buffer_views, decoded, &bytes, decoded_buffer);
            }
        }
    }
    Ok(())
}

/// Appends `bytes` to the decoded buffer, `buffer`, and points the accessor at them through a new
/// buffer view.
fn point_at(accessor: &mut json::Accessor, views: &mut Vec<json::buffer::View>, decoded: &mut Vec<u8>, bytes: &[u8], buffer: usize) {
    let offset = decoded.len();
    decoded.extend_from_slice(bytes);
    view_over(accessor, views, decoded, offset, buffer);
}

/// Points the accessor through a new buffer view at the decoded buffer's bytes from `offset` to its
/// end, and pads the buffer to 4 bytes for the next.
fn view_over(accessor: &mut json::Accessor, views: &mut Vec<json::buffer::View>, decoded: &mut Vec<u8>, offset: usize, buffer: usize) {
    let length = decoded.len() - offset;
    decoded.resize(decoded.len().next_multiple_of(4), 0);
    views.push(json::buffer::View {
        buffer: json::Index::new(buffer as u32),
        byte_length: length.into(),
        byte_offset: Some(offset.into()),
        byte_stride: None,
        name: None,
        target: None,
        extensions: None,
        extras: Default::default(),
    });
    accessor.buffer_view = Some(json::Index::new(views.len() as u32 - 1));
    accessor.byte_offset = None;
    accessor.sparse = None;
}

/// Draco's values in the accessor's component type. Draco stores an integer accessor's values as
/// integers (a normalized one's too, as the stored integers), exact in the floats they are read as.
fn encode_as(values: &[f32], component: json::accessor::ComponentType) -> Vec<u8> {
    use json::accessor::ComponentType;
    match component {
        ComponentType::F32 => values.iter().flat_map(|v| v.to_le_bytes()).collect(),
        ComponentType::I8 => values.iter().map(|&v| v.round() as i8 as u8).collect(),
        ComponentType::U8 => values.iter().map(|&v| v.round() as u8).collect(),
        ComponentType::I16 => values.iter().flat_map(|&v| (v.round() as i16).to_le_bytes()).collect(),
        ComponentType::U16 => values.iter().flat_map(|&v| (v.round() as u16).to_le_bytes()).collect(),
        ComponentType::U32 => values.iter().flat_map(|&v| (v.round() as u32).to_le_bytes()).collect(),
    }
}
