//! The binary frame of the API: a JSON header and f32 data in one body.

use serde_json::Value;

/// `u32` little-endian length of the JSON header, the header, zero padding
/// to a multiple of 4 bytes, then the f32 values little-endian.
pub fn frame(header: &Value, floats: &[f32]) -> Vec<u8> {
    let text = header.to_string();
    let mut out = Vec::with_capacity(8 + text.len() + 4 * floats.len());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(text.as_bytes());
    while out.len() % 4 != 0 {
        out.push(b' ');
    }
    out.extend(floats.iter().flat_map(|f| f.to_le_bytes()));
    out
}

/// f32 little-endian bytes of vectors, minus `origin`.
pub fn vec3_bytes(points: &[fairline::Vec3], origin: fairline::Vec3) -> Vec<u8> {
    let mut out = Vec::with_capacity(points.len() * 12);
    for p in points {
        let q = *p - origin;
        for c in [q.x, q.y, q.z] {
            out.extend_from_slice(&(c as f32).to_le_bytes());
        }
    }
    out
}
