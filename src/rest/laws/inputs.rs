//! The per-face inputs of the growth laws ([`GrowthInputs`]), read once from the mesh's fields
//! and the `[growth]` settings: the surface moisture, the conformal factor and the machine
//! direction.

use crate::math::{Real, Vec3};
use crate::mesh::{Mesh, MeshError};
use crate::rest::barycentric_direction;
use crate::settings::Settings;

/// A per-face scalar field with a uniform fallback, checked finite (naming the face).
fn face_values(mesh: &Mesh, name: &str, uniform: Real) -> Result<Vec<Real>, MeshError> {
    match mesh.face_field(name, 1)? {
        Some(f) => {
            if let Some(i) = f.data.iter().position(|v| !v.is_finite()) {
                return Err(mesh.invalid(format!("face field '{name}' is not finite at face {i}")));
            }
            Ok(f.data.clone())
        }
        None => Ok(vec![uniform; mesh.faces.len()]),
    }
}

/// Per-face inputs of the growth laws, read once from the mesh fields and settings.
#[derive(Clone, Debug, Default)]
pub struct GrowthInputs {
    /// Moisture at the top surface.
    pub moisture_top: Vec<Real>,
    /// Moisture at the bottom surface.
    pub moisture_bottom: Vec<Real>,
    /// Conformal factor s of the isotropic law.
    pub s: Vec<Real>,
    /// Machine direction per face: barycentric coordinates, and the unit 3D vector in the face
    /// plane (for the diffusivity). Empty unless the law or the diffusion needs it.
    pub direction: Vec<([Real; 2], Vec3)>,
    /// `growth.temperature_top`, `growth.temperature_bottom` (K): the highest temperatures
    /// reached without `[temperature]`.
    pub temperature: (Real, Real),
    /// Per face, the swelling coefficients: `uniform`, replaced on `growth.regions` and by the
    /// face fields `growth_mu`, … (empty when neither is given).
    pub coef: Vec<super::Coefficients>,
    /// The uniform coefficients of `[growth]`.
    pub uniform: super::Coefficients,
    /// Per face, the stored original forms `(â, b̂)` of a law that relaxes toward them (from the
    /// vertex field `original_positions`), else empty.
    pub relaxed: Vec<(crate::math::Sym2, crate::math::Sym2)>,
    /// `growth.law`.
    pub which: crate::settings::GrowthLaw,
    /// The growth law with its coefficients (`None`: no growth law).
    pub law: Option<std::sync::Arc<dyn super::RestLaw>>,
}

impl GrowthInputs {
    /// True when the uniform or some face's coefficients give a bilayer layer's coefficient
    /// across the machine direction ([`super::Coefficients::gives_across`]).
    pub fn gives_across(&self) -> bool {
        self.uniform.gives_across() || self.coef.iter().any(super::Coefficients::gives_across)
    }

    /// Reads them for `settings.growth.law` (the machine direction also for `[moisture]`, whose
    /// diffusivity follows it). Errors name the field or key and the face.
    pub fn read(mesh: &Mesh, settings: &Settings) -> Result<Self, MeshError> {
        let g = &settings.growth;
        let law = super::law(&g.model());
        let mut out = GrowthInputs {
            moisture_top: face_values(mesh, "moisture_top", g.moisture_top)?,
            moisture_bottom: face_values(mesh, "moisture_bottom", g.moisture_bottom)?,
            s: match (mesh.face_field("growth_factor", 1)?, &g.s) {
                (Some(_), _) => face_values(mesh, "growth_factor", 0.0)?,
                (None, Some(s)) => settings_field(mesh, s, "growth.s")?,
                (None, None) if law.as_ref().is_some_and(|l| l.needs_s()) => {
                    return Err(mesh.invalid(format!(
                        "growth.law = \"{}\" needs its growth factor s: give growth.s (a number \
                         or an expression of x, y) or the face field 'growth_factor'",
                        g.law.name()
                    )))
                }
                (None, None) => vec![0.0; mesh.faces.len()],
            },
            direction: Vec::new(),
            temperature: (g.temperature_top, g.temperature_bottom),
            coef: Vec::new(),
            uniform: super::Coefficients {
                mu: g.mu.unwrap_or(0.0),
                mu_perp: g.mu_perp.unwrap_or(0.0),
                mu_top: g.mu_top.unwrap_or(0.0),
                mu_bottom: g.mu_bottom.unwrap_or(0.0),
                mu_top_perp: g.mu_top_perp,
                mu_bottom_perp: g.mu_bottom_perp,
                mu_through: g.mu_through.unwrap_or(0.0),
                print_thickness: g.print_thickness.unwrap_or(0.0),
                print_modulus_ratio: g.print_modulus_ratio.unwrap_or(1.0),
            },
            which: g.law,
            law: law.clone(),
            relaxed: Vec::new(),
        };
        out.coef = per_face_coefficients(mesh, settings, out.uniform)?;
        // A bilayer reads the machine direction where its layers' coefficients across it are
        // given, from any source.
        if law.as_ref().is_some_and(|l| l.needs_direction())
            || (g.law == crate::config::growth::GrowthLaw::Bilayer && out.gives_across())
            || settings.moisture.enabled
            || settings.temperature.enabled
        {
            let dirs = mesh.face_field("machine_direction", 3)?;
            for f in 0..mesh.faces.len() {
                let (d, what) = match dirs {
                    Some(df) => (
                        Vec3::from_column_slice(df.get(f)),
                        "face field 'machine_direction'",
                    ),
                    None => (Vec3::from(g.machine_direction), "growth.machine_direction"),
                };
                let d2 = barycentric_direction(mesh, f, &d).ok_or_else(|| {
                    mesh.invalid(format!(
                        "{what} at face {f} is [{}, {}, {}]: it must be finite, non-zero and not \
                         normal to the face",
                        d.x, d.y, d.z
                    ))
                })?;
                let [p0, p1, p2] = mesh.face_positions(f);
                let d3 = ((p1 - p0) * d2[0] + (p2 - p0) * d2[1]).normalize();
                out.direction.push((d2, d3));
            }
        }
        Ok(out)
    }
}

/// Sets one coefficient of [`super::Coefficients`].
type Slot = fn(&mut super::Coefficients, Real);

/// The face fields of the per-face coefficients, and which coefficient each sets, in the order
/// of [`crate::config::growth::GrowthRegion::values`].
pub(crate) const COEFFICIENT_FIELDS: [(&str, Slot); 9] = [
    ("growth_mu", |c, v| c.mu = v),
    ("growth_mu_perp", |c, v| c.mu_perp = v),
    ("growth_mu_top", |c, v| c.mu_top = v),
    ("growth_mu_bottom", |c, v| c.mu_bottom = v),
    ("growth_mu_top_perp", |c, v| c.mu_top_perp = Some(v)),
    ("growth_mu_bottom_perp", |c, v| c.mu_bottom_perp = Some(v)),
    ("growth_mu_through", |c, v| c.mu_through = v),
    ("growth_print_thickness", |c, v| c.print_thickness = v),
    ("growth_print_modulus_ratio", |c, v| {
        c.print_modulus_ratio = v
    }),
];

/// Per-face coefficients: `uniform`, replaced on each `growth.regions` entry's faces by the
/// coefficients it gives, then by the face fields `growth_mu`, … (checked finite and within
/// ±`MAX_MOISTURE`, naming the face). Empty when there are neither regions nor fields.
fn per_face_coefficients(
    mesh: &Mesh,
    settings: &Settings,
    uniform: super::Coefficients,
) -> Result<Vec<super::Coefficients>, MeshError> {
    let regions = &settings.growth.regions;
    let mut fields = Vec::new();
    for (name, slot) in COEFFICIENT_FIELDS {
        if let Some(f) = mesh.face_field(name, 1)? {
            fields.push((name, slot, f.data.clone()));
        }
    }
    if regions.is_empty() && fields.is_empty() {
        return Ok(Vec::new());
    }
    let mut coef = vec![uniform; mesh.faces.len()];
    for (i, r) in regions.iter().enumerate() {
        let faces = mesh.faces_matching(
            &r.tags,
            r.inside.as_ref().map(|b| (b.min, b.max)),
            &format!("growth.regions[{i}]"),
        )?;
        for f in faces {
            for ((_, v), (_, slot)) in r.values().into_iter().zip(COEFFICIENT_FIELDS) {
                if let Some(v) = v {
                    slot(&mut coef[f], v);
                }
            }
        }
    }
    let max = crate::config::limits::MAX_MOISTURE;
    for (name, slot, data) in fields {
        for (f, &v) in data.iter().enumerate() {
            if !(name.starts_with("growth_print_") || v.is_finite() && v.abs() <= max) {
                return Err(mesh.invalid(format!(
                    "face field '{name}' at face {f} is {v}: a swelling coefficient must be \
                     finite and within ±{max}"
                )));
            }
            if let Err(e) = crate::config::growth::print_range(name, name, v) {
                return Err(mesh.invalid(format!("face field '{name}' at face {f}: {}", e.reason)));
            }
            slot(&mut coef[f], v);
        }
    }
    Ok(coef)
}

/// A settings field (number or expression of x, y) at every face's reference centroid; a
/// non-finite value is an error naming the face.
pub fn settings_field(
    mesh: &Mesh,
    field: &crate::settings::Field,
    key: &str,
) -> Result<Vec<Real>, MeshError> {
    let e = field
        .compile()
        .map_err(|e| mesh.invalid(format!("{key}: {e}")))?;
    (0..mesh.faces.len())
        .map(|f| {
            let [p0, p1, p2] = mesh.face_positions(f);
            let c = (p0 + p1 + p2) / 3.0;
            let v = e.eval(c.x, c.y);
            if v.is_finite() {
                Ok(v)
            } else {
                Err(mesh.invalid(format!(
                    "{key} is {v} at face {f} (centroid x = {}, y = {})",
                    c.x, c.y
                )))
            }
        })
        .collect()
}
