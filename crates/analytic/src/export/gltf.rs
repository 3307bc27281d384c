//! A glTF 2.0 binary (`.glb`): one UV sphere of radius 1 (positions and
//! unit normals, 16-bit indices, no degenerate triangles: the poles are
//! single vertices with triangle fans) carrying the fitted material as
//! `pbrMetallicRoughness` with `KHR_materials_specular`.

use crate::Principled;
use serde_json::{Value, json};

/// Rings between the poles, and vertices around each ring.
const STACKS: usize = 32;
const SLICES: usize = 64;

/// Positions (= normals, radius 1) and triangle indices of the sphere.
fn sphere() -> (Vec<[f32; 3]>, Vec<u16>) {
    let mut v = vec![[0.0, 1.0, 0.0]];
    for i in 1..STACKS {
        let theta = std::f64::consts::PI * i as f64 / STACKS as f64;
        for j in 0..SLICES {
            let phi = 2.0 * std::f64::consts::PI * j as f64 / SLICES as f64;
            let (st, ct) = theta.sin_cos();
            let (sp, cp) = phi.sin_cos();
            v.push([(st * cp) as f32, ct as f32, (-st * sp) as f32]);
        }
    }
    v.push([0.0, -1.0, 0.0]);
    let ring = |i: usize, j: usize| (1 + (i - 1) * SLICES + j % SLICES) as u16;
    let south = (v.len() - 1) as u16;
    let mut idx = Vec::new();
    for j in 0..SLICES {
        // Counter-clockwise seen from outside.
        idx.extend([0, ring(1, j), ring(1, j + 1)]);
        idx.extend([ring(STACKS - 1, j), south, ring(STACKS - 1, j + 1)]);
    }
    for i in 1..STACKS - 1 {
        for j in 0..SLICES {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            idx.extend([a, c, b, b, c, d]);
        }
    }
    (v, idx)
}

/// The glTF material of `p` named `name`.
pub fn material(p: &Principled, name: &str) -> Value {
    let [r, g, b] = p.base_color;
    json!({
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [r, g, b, 1.0],
            "metallicFactor": p.metallic,
            "roughnessFactor": p.roughness,
        },
        "extensions": {
            "KHR_materials_specular": {
                "specularFactor": p.specular,
                "specularColorFactor": p.specular_color,
            }
        }
    })
}

/// The `.glb` bytes of a scene with one sphere of material `p`; `notes`
/// go into the asset's `extras` (the fit's errors and how they were measured).
pub fn glb(p: &Principled, name: &str, notes: Value) -> Vec<u8> {
    let (vertices, indices) = sphere();
    let mut bin = Vec::new();
    for v in &vertices {
        for c in v {
            bin.extend(c.to_le_bytes());
        }
    }
    let positions_len = bin.len();
    for v in &vertices {
        for c in v {
            bin.extend(c.to_le_bytes());
        }
    }
    let normals_len = bin.len() - positions_len;
    for i in &indices {
        bin.extend(i.to_le_bytes());
    }
    let indices_len = bin.len() - positions_len - normals_len;
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let doc = json!({
        "asset": {"version": "2.0", "generator": "brdf-atlas export", "extras": notes},
        "extensionsUsed": ["KHR_materials_specular"],
        "scene": 0,
        "scenes": [{"name": name, "nodes": [0]}],
        "nodes": [{"name": name, "mesh": 0}],
        "meshes": [{"name": name, "primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1},
            "indices": 2,
            "material": 0,
            "mode": 4,
        }]}],
        "materials": [material(p, name)],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": vertices.len(), "type": "VEC3",
             "min": [-1.0, -1.0, -1.0], "max": [1.0, 1.0, 1.0]},
            {"bufferView": 1, "componentType": 5126, "count": vertices.len(), "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": indices.len(), "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": positions_len, "target": 34962},
            {"buffer": 0, "byteOffset": positions_len, "byteLength": normals_len, "target": 34962},
            {"buffer": 0, "byteOffset": positions_len + normals_len, "byteLength": indices_len, "target": 34963},
        ],
        "buffers": [{"byteLength": bin.len()}],
    });
    let mut text = doc.to_string().into_bytes();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let total = 12 + 8 + text.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(text);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sphere_is_closed_and_wound_outwards() {
        let (v, idx) = sphere();
        assert!(v.len() < 65536);
        // Every edge of a closed mesh is used once in each direction.
        let mut edges = std::collections::BTreeMap::new();
        let mut volume = 0.0f64;
        for t in idx.chunks(3) {
            assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
            let [a, b, c] = [0, 1, 2].map(|k| v[t[k] as usize].map(f64::from));
            volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0;
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1);
            assert_eq!(edges.get(&(b, a)), Some(&1));
        }
        // Outward winding: positive volume, close to the unit ball's.
        let ball = 4.0 / 3.0 * std::f64::consts::PI;
        assert!(volume > 0.98 * ball && volume < ball, "{volume}");
    }

    #[test]
    fn the_container_has_its_chunks_aligned() {
        let bytes = glb(&Principled::default(), "m", json!({}));
        assert_eq!(&bytes[0..4], b"glTF");
        assert_eq!(
            u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
            bytes.len()
        );
        let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        assert_eq!(json_len % 4, 0);
        let doc: Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
        let bin_len = doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize;
        assert_eq!(20 + json_len + 8 + bin_len, bytes.len());
        assert_eq!(&bytes[20 + json_len + 4..20 + json_len + 8], b"BIN\0");
    }
}
