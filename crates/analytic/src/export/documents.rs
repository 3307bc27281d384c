//! The fitted material as a MaterialX document (Autodesk Standard Surface)
//! and as a Mitsuba 3 `principled` BSDF dictionary (JSON, for
//! `mi.load_dict(json.load(f))`).
//!
//! Parameters carry over by name: glTF's base colour, metallic, roughness,
//! specular factor and specular colour are Standard Surface's `base_color`
//! (with `base` 1), `metalness`, `specular_roughness`, `specular` and
//! `specular_color` and `specular_IOR` (glTF's `ior`), the mapping
//! MaterialX's own glTF translation uses. Mitsuba's `principled` has
//! `base_color`, `metallic` and `roughness` alike; its dielectric F0 comes
//! from `eta` alone, so `eta` is chosen to give glTF's F0
//! `((ior - 1) / (ior + 1))^2 specularFactor luminance(specularColor)`,
//! and its `spec_tint` tints towards the base colour's hue, not to a colour
//! of its own, so it stays 0 and the specular colour's hue is lost.

use crate::Principled;
use serde_json::{Value, json};

/// A MaterialX identifier from `name`: letters, digits and `_`, not
/// starting with a digit.
pub fn identifier(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if !s.starts_with(|c: char| c.is_ascii_alphabetic()) {
        s.insert(0, 'm');
    }
    s
}

fn color(c: [f64; 3]) -> String {
    format!("{:.6}, {:.6}, {:.6}", c[0], c[1], c[2])
}

/// Escape `text` for an XML comment (no `--`).
fn comment(text: &str) -> String {
    text.replace("--", "- -")
}

/// The MaterialX document of `p` named `name`, with `note` (the fit error)
/// as a comment.
pub fn materialx(p: &Principled, name: &str, note: &str) -> String {
    let id = identifier(name);
    format!(
        r#"<?xml version="1.0"?>
<materialx version="1.39" colorspace="lin_rec709">
  <!-- {note} -->
  <standard_surface name="SR_{id}" type="surfaceshader">
    <input name="base" type="float" value="1.0" />
    <input name="base_color" type="color3" value="{base}" />
    <input name="diffuse_roughness" type="float" value="0.0" />
    <input name="metalness" type="float" value="{metallic:.6}" />
    <input name="specular" type="float" value="{specular:.6}" />
    <input name="specular_color" type="color3" value="{spec_color}" />
    <input name="specular_roughness" type="float" value="{roughness:.6}" />
    <input name="specular_IOR" type="float" value="{ior:.6}" />
  </standard_surface>
  <surfacematerial name="M_{id}" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_{id}" />
  </surfacematerial>
</materialx>
"#,
        note = comment(note),
        base = color(p.base_color),
        metallic = p.metallic,
        specular = p.specular,
        spec_color = color(p.specular_color),
        roughness = p.roughness,
        ior = p.ior,
    )
}

/// Rec. 709 luminance of a linear colour.
fn luminance(c: [f64; 3]) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Mitsuba's `eta` for the dielectric F0 of `p` (`specular` and the
/// tint's luminance folded in): `F0 = ((eta - 1) / (eta + 1))^2`.
pub fn mitsuba_eta(p: &Principled) -> f64 {
    let r0 = ((p.ior - 1.0) / (p.ior + 1.0)).powi(2) * p.specular * luminance(p.specular_color);
    let r = r0.clamp(0.0, 0.99).sqrt();
    // Mitsuba needs eta > 1: a material without a dielectric reflection gets the least.
    ((1.0 + r) / (1.0 - r)).max(1.0 + 1e-4)
}

/// The Mitsuba 3 `principled` dictionary of `p`.
pub fn mitsuba(p: &Principled) -> Value {
    json!({
        "type": "principled",
        "base_color": {"type": "rgb", "value": p.base_color},
        "metallic": p.metallic,
        "roughness": p.roughness,
        "eta": mitsuba_eta(p),
        "spec_tint": 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_are_materialx_names() {
        assert_eq!(identifier("blue-metallic-paint"), "blue_metallic_paint");
        assert_eq!(identifier("0.30,-0.50"), "m0_30__0_50");
    }

    #[test]
    fn gltf_default_specular_is_mitsuba_default() {
        let d = mitsuba(&Principled::default());
        assert!((d["eta"].as_f64().unwrap() - 1.5).abs() < 1e-12);
        assert!(materialx(&Principled::default(), "a--b", "x -- y").contains("x - - y"));
    }
}
