//! `shellsim design DESIGN.toml MESH TARGET --out DIR`: reads and checks everything first
//! (nothing is written for bad input), designs, and writes
//!
//! * `designed.vtk`: the input mesh with the designed fields, and `settings.toml`: the scene
//!   that reproduces the designed shape with `shellsim settings.toml designed.vtk`;
//! * `shape.vtk`: the designed equilibrium, aligned onto the target;
//! * `iterations/iteration_NNNNN.vtk` and `iterations.pvd`: the shape per iteration (aligned),
//!   with the design and each vertex's distance to the target;
//! * `design_log.csv`: the objective per iteration; `design_summary.json`: how it ended, the
//!   numbers and where the time went.

use super::curvature::{face_fields, Curvature};
use super::lbfgs::{minimise, Iterate, Options, Stop};
use super::objective::{bounding_diagonal, DistanceTerm, Points, Shape, Smoothness, Sobolev};
use super::surface::Surface;
use super::variables::Chain;
use super::{DesignTiming, Evaluated, Problem};
use crate::config::design::{Design, Method, Objective, Start, Variable};
use crate::config::growth::GrowthLaw;
use crate::math::{sym_det, Real, Vec3};
use crate::mesh::io::{read_mesh, series_xml, write_atomic, write_mesh, Format};
use crate::mesh::{Field, Mesh, Topology};
use crate::model::Scene;
use crate::rest::push_forward;
use crate::settings::{Settings, TargetForms};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A design's bad input or failed output (exit 2), with the file, key or face it concerns.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct DesignError(pub String);

impl DesignError {
    fn at(path: &Path, reason: impl std::fmt::Display) -> Self {
        DesignError(format!("{}: {reason}", path.display()))
    }
}

/// What `shellsim design` was asked.
#[derive(Clone, Debug)]
pub struct Request {
    /// The design file (a settings file with a `[design]` section).
    pub design: PathBuf,
    /// The flat (or curved) reference mesh to design.
    pub mesh: PathBuf,
    /// The target shape.
    pub target: PathBuf,
    /// The output folder.
    pub out: PathBuf,
    /// Replace an earlier design's output.
    pub overwrite: bool,
    /// `--set` overrides of the settings part.
    pub set: Vec<String>,
    /// No line per iteration on stderr.
    pub quiet: bool,
}

/// How a design ended.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Whether it converged (tolerance, target distance or a zero projected gradient).
    pub converged: bool,
    /// Why it stopped.
    pub reason: String,
    /// Design iterations.
    pub iterations: usize,
    /// The objective reached.
    pub objective: Real,
    /// The RMS distance to the target over its size.
    pub distance: Real,
}

/// Everything read and checked: the scene, the design, the chain, the start and the target.
pub struct Prepared {
    /// The scene every design is solved in.
    pub scene: Scene,
    /// The `[design]` section.
    pub design: Design,
    /// The input mesh as read (the designed mesh keeps its fields).
    pub input: Mesh,
    /// The target mesh.
    pub target: Mesh,
    /// The target mean and Gauss curvature per face of the design mesh (1/m, 1/m²), when the
    /// objective has those terms.
    pub curvature_targets: (Option<Vec<Real>>, Option<Vec<Real>>),
    /// The settings part of the design file, as TOML.
    pub settings_table: toml::Table,
    chain: Chain,
    start: Vec<Real>,
}

/// The designs a growth chain accepts.
const GROWTH_LAWS: [GrowthLaw; 3] = [
    GrowthLaw::Isotropic,
    GrowthLaw::IsotropicInPlane,
    GrowthLaw::IsotropicMetricOnly,
];

/// Reads and checks the design file, the mesh and the target; nothing is written.
pub fn prepare(req: &Request) -> Result<Prepared, DesignError> {
    let name = req.design.display().to_string();
    let text = std::fs::read_to_string(&req.design)
        .map_err(|e| DesignError::at(&req.design, format!("cannot read the design file: {e}")))?;
    let (settings_text, design_text) = crate::config::design::split(&text);
    let design = crate::config::design::parse(&design_text)
        .map_err(|e| DesignError(format!("{name}: {e}")))?;
    if design_text.trim().is_empty() {
        return Err(DesignError::at(
            &req.design,
            "a design file needs a [design] section (see docs/design.md); to run a scene use \
             `shellsim SETTINGS MESH`",
        ));
    }
    let settings = Settings::from_str_with(&settings_text, &name, &req.set)
        .map_err(|e| DesignError(e.to_string()))?;
    let mut settings_table: toml::Table =
        toml::from_str(&settings_text).map_err(|e| DesignError::at(&req.design, e.to_string()))?;
    crate::settings::apply_overrides(&mut settings_table, &req.set)
        .map_err(|e| DesignError(e.to_string()))?;
    designable(&settings, &design)
        .map_err(|(k, r)| DesignError(format!("{name}: invalid '{k}': {r}")))?;
    let input = read_mesh(&req.mesh).map_err(|e| DesignError(e.to_string()))?;
    let scene = Scene::build(input.clone(), settings).map_err(|e| DesignError(e.to_string()))?;
    let target = read_target(&req.target, &scene, &design)?;
    let interior = |o: &[usize; 3]| !o.contains(&crate::mesh::topology::NONE);
    if design.mean_curvature_weight + design.gauss_curvature_weight > 0.0
        && !scene.body.topo.opposite_vertex.iter().any(interior)
    {
        let key = if design.mean_curvature_weight > 0.0 {
            "design.mean_curvature_weight"
        } else {
            "design.gauss_curvature_weight"
        };
        return Err(DesignError(format!(
            "{name}: invalid '{key}': the curvature terms compare the faces with three \
             neighbours, and no face of {} has three",
            req.mesh.display()
        )));
    }
    let curvature_targets = curvature_targets(&req.target, &target, &scene, &design)?;
    let (chain, mut start) = chain_and_start(&scene, &design)
        .map_err(|(k, r)| DesignError(format!("{name}: invalid '{k}': {r}")))?;
    check_bounds(&design, &chain, &start)
        .map_err(|(k, r)| DesignError(format!("{name}: invalid '{k}': {r}")))?;
    if design.start == Some(Start::Target) {
        start = fitted_start(&req.target, &target, &scene, &design, &chain, &start)?;
    }
    Ok(Prepared {
        scene,
        design,
        input,
        target,
        curvature_targets,
        settings_table,
        chain,
        start,
    })
}

/// The scenes a design can be solved in: static, with the Koiter membrane, without contact,
/// obstacles or the diffusion fields (whose states are not design data). Errors: (key, why).
fn designable(s: &Settings, d: &Design) -> Result<(), (String, String)> {
    let no = |k: &str, why: &str| Err((k.to_string(), why.to_string()));
    if s.solver.mode != crate::settings::Mode::Static {
        return no(
            "solver.mode",
            "a design is made of static equilibria: solver.mode = \"static\"",
        );
    }
    if s.material.model != crate::config::material::MaterialModel::Koiter {
        return no(
            "material.model",
            "the rest sensitivities are derived for the Koiter membrane (material.model = \"koiter\")",
        );
    }
    if s.material.bend_stiffening.is_some() {
        return no(
            "material.bend_stiffening",
            "bend stiffening has no rest sensitivities",
        );
    }
    for (on, key) in [
        (s.contact.enabled, "contact.enabled"),
        (s.self_contact.enabled, "self_contact.enabled"),
        (s.slides.enabled, "slides.enabled"),
        (s.moisture.enabled, "moisture.enabled"),
        (s.temperature.enabled, "temperature.enabled"),
        (!s.obstacles.is_empty(), "obstacles"),
    ] {
        if on {
            return no(
                key,
                "a design solves the sheet alone: contact, obstacles, slides and the moisture \
                 and temperature fields are not designed through",
            );
        }
    }
    let (law, target) = (s.growth.law, s.rest.target);
    let ok = match d.variable {
        Variable::Growth => GROWTH_LAWS.contains(&law) && target == TargetForms::None,
        Variable::Director => law == GrowthLaw::None && target == TargetForms::Lce,
        Variable::Forms => {
            law == GrowthLaw::None
                && matches!(
                    target,
                    TargetForms::None | TargetForms::Uniform | TargetForms::Mesh
                )
        }
        Variable::Bbar => {
            law == GrowthLaw::None
                && matches!(
                    target,
                    TargetForms::None | TargetForms::Uniform | TargetForms::Mesh
                )
        }
        Variable::Swelling => law == GrowthLaw::Bilayer && target == TargetForms::None,
        Variable::Thickness => law == GrowthLaw::None || GROWTH_LAWS.contains(&law),
    };
    if !ok {
        let needs = match d.variable {
            Variable::Growth => {
                "the growth factor of growth.law = \"isotropic\", \"isotropic_in_plane\" or \
                 \"isotropic_metric_only\" (with rest.target = \"none\")"
            }
            Variable::Director => {
                "the director angle of rest.target = \"lce\" (with growth.law = \"none\")"
            }
            Variable::Forms => {
                "the rest forms of rest.target = \"none\", \"uniform\" or \"mesh\" (with \
                 growth.law = \"none\")"
            }
            Variable::Bbar => {
                "the rest b̄ of rest.target = \"none\", \"uniform\" or \"mesh\" (with \
                 growth.law = \"none\")"
            }
            Variable::Swelling => {
                "the layer strains of growth.law = \"bilayer\" (with rest.target = \"none\")"
            }
            Variable::Thickness => {
                "the rest thickness under growth.law = \"none\", \"isotropic\", \
                 \"isotropic_in_plane\" or \"isotropic_metric_only\" (laws whose forms do not \
                 depend on the thickness)"
            }
        };
        return Err((
            "design.variable".into(),
            format!(
                "\"{}\" designs {needs}; this file has growth.law = \"{}\" and rest.target = \"{}\", \
                 whose law has no such variable",
                d.variable.name(),
                law.name(),
                target.name()
            ),
        ));
    }
    Ok(())
}

/// The target mesh: not empty, and with the design mesh's connectivity when the objective
/// compares vertices (point to point, or curvatures computed from the target's geometry).
fn read_target(path: &Path, scene: &Scene, d: &Design) -> Result<Mesh, DesignError> {
    let t = read_mesh(path).map_err(|e| DesignError(e.to_string()))?;
    if t.positions.is_empty() || t.faces.is_empty() {
        return Err(DesignError::at(
            path,
            "the target is empty: it has no faces",
        ));
    }
    if d.distance_weight > 0.0 && d.objective == Objective::Points {
        same_connectivity(
            path,
            &t,
            scene,
            "design.objective = \"points\" compares each vertex with its own",
        )?;
    }
    Ok(t)
}

/// Checks that the target `t` has the design mesh's connectivity, which `why` needs.
fn same_connectivity(path: &Path, t: &Mesh, scene: &Scene, why: &str) -> Result<(), DesignError> {
    let nv = scene.body.num_vertices();
    let faces = scene.body.input_faces();
    if t.positions.len() != nv || t.faces.len() != faces.len() {
        return Err(DesignError::at(
            path,
            format!(
                "{why}, which needs the design mesh's connectivity: the target has {} vertices \
                 and {} faces, the mesh {} and {}",
                t.positions.len(),
                t.faces.len(),
                nv,
                faces.len()
            ),
        ));
    }
    for (f, (a, b)) in faces.iter().zip(&t.faces).enumerate() {
        let same = (0..3).any(|k| (0..3).all(|i| a[i] == b[(i + k) % 3]));
        if !same {
            return Err(DesignError::at(
                path,
                format!(
                    "the target's face {f} is {b:?}, the mesh's {a:?}: {why}, which needs the \
                     same connectivity"
                ),
            ));
        }
    }
    Ok(())
}

/// The target curvatures per face of the design mesh for the curvature terms the design
/// weighs: the target's face fields `mean_curvature` (1/m) and `gauss_curvature` (1/m²) when it
/// has them, else the curvatures of the target's own geometry (which then needs the design
/// mesh's connectivity).
#[allow(clippy::type_complexity)]
fn curvature_targets(
    path: &Path,
    t: &Mesh,
    scene: &Scene,
    d: &Design,
) -> Result<(Option<Vec<Real>>, Option<Vec<Real>>), DesignError> {
    let nf = scene.body.num_faces();
    let mut geometry: Option<Vec<Option<(Real, Real)>>> = None;
    let mut field =
        |name: &str, weight: Real, which: usize| -> Result<Option<Vec<Real>>, DesignError> {
            if weight <= 0.0 {
                return Ok(None);
            }
            if let Some(f) = t.face_fields.get(name) {
                if f.components != 1 {
                    return Err(DesignError::at(
                        path,
                        format!("the face field '{name}' must have one number per face"),
                    ));
                }
                let v = &f.data;
                if v.len() != nf {
                    return Err(DesignError::at(
                        path,
                        format!(
                            "the face field '{name}' has {} values; the design mesh has {nf} faces",
                            v.len()
                        ),
                    ));
                }
                if let Some(face) = v.iter().position(|x| !x.is_finite()) {
                    return Err(DesignError::at(
                        path,
                        format!("the face field '{name}' is not finite at face {face}"),
                    ));
                }
                return Ok(Some(v.to_vec()));
            }
            if geometry.is_none() {
                same_connectivity(
                    path,
                    t,
                    scene,
                    &format!(
                        "the target has no face field '{name}', so its curvatures come from its \
                     geometry face by face"
                    ),
                )?;
                let topo = Topology::build(t).map_err(|e| DesignError(e.to_string()))?;
                geometry = Some(face_fields(t, &topo, &t.positions));
            }
            let g = geometry.as_ref().expect("computed above");
            Ok(Some(
                g.iter()
                    .map(|c| c.map_or(0.0, |c| if which == 0 { c.0 } else { c.1 }))
                    .collect(),
            ))
        };
    let mean = field("mean_curvature", d.mean_curvature_weight, 0)?;
    let gauss = field("gauss_curvature", d.gauss_curvature_weight, 1)?;
    Ok((mean, gauss))
}

/// The chain of the design's variable and where it starts: `design.start` everywhere, or the
/// scene's own design (its growth factor, director or rest forms). Errors: (key, why).
pub fn chain_and_start(scene: &Scene, d: &Design) -> Result<(Chain, Vec<Real>), (String, String)> {
    let body = &scene.body;
    let nf = body.num_faces();
    let rest = &body.rest;
    let flat = || {
        if body.mesh.is_flat_xy() {
            Ok(())
        } else {
            Err((
                "design.variable".to_string(),
                format!(
                    "\"{}\" is given in reference Cartesian (x, y) coordinates, which needs a flat \
                     mesh in a plane z = const",
                    d.variable.name()
                ),
            ))
        }
    };
    let (chain, own): (Chain, Vec<Real>) = match d.variable {
        Variable::Growth => {
            let reference = (0..nf).map(|f| (rest.abar0[f], rest.bbar0[f])).collect();
            // Every isotropic law has ā = e^{2s} a⁰.
            let s = (0..nf)
                .map(|f| 0.25 * (sym_det(&rest.abar1[f]) / sym_det(&rest.abar0[f])).ln())
                .collect();
            (Chain::growth(scene.settings.growth.law, reference), s)
        }
        Variable::Director => {
            flat()?;
            let frames = Chain::frames(&body.mesh);
            let theta = rest
                .lce
                .iter()
                .zip(&frames)
                .map(|(l, t)| {
                    let m = push_forward(t, &l.p);
                    0.5 * (2.0 * m[1]).atan2(m[0] - m[2])
                })
                .collect();
            let stretch = rest.lce.iter().map(|l| (l.lambda, l.nu)).collect();
            (Chain::Director { stretch, frames }, theta)
        }
        Variable::Forms => {
            flat()?;
            let frames = Chain::frames(&body.mesh);
            let p = (0..nf)
                .flat_map(|f| {
                    let a = push_forward(&frames[f], &rest.abar1[f]);
                    let b = push_forward(&frames[f], &rest.bbar1[f]);
                    [a[0], a[1], a[2], b[0], b[1], b[2]]
                })
                .collect();
            (Chain::Forms { frames }, p)
        }
        Variable::Bbar => {
            flat()?;
            let frames = Chain::frames(&body.mesh);
            let p = (0..nf)
                .flat_map(|f| {
                    let b = push_forward(&frames[f], &rest.bbar1[f]);
                    [b[0], b[1], b[2]]
                })
                .collect();
            let abar = rest.abar1.clone();
            (Chain::Bbar { frames, abar }, p)
        }
        Variable::Swelling => {
            let crate::config::growth::GrowthModel::Bilayer { laminate, .. } =
                scene.settings.growth.model()
            else {
                unreachable!("designable() checked the law")
            };
            let g = &body.growth;
            let mut basis = Vec::with_capacity(nf);
            let mut ratio = Vec::with_capacity(nf);
            let mut shapes = Vec::with_capacity(nf);
            let mut gel_faces = Vec::with_capacity(nf);
            let mut own = Vec::with_capacity(2 * nf);
            for f in 0..nf {
                let c = g.coef.get(f).copied().unwrap_or(g.uniform);
                let (top, bottom) = (c.top_layer(), c.bottom_layer());
                let shape = [Chain::layer_shape(top), Chain::layer_shape(bottom)];
                let d = g.direction.get(f).map_or([1.0, 0.0], |d| d.0);
                let (mt, mb) = (g.moisture_top[f], g.moisture_bottom[f]);
                if mt == 0.0 || mb == 0.0 {
                    return Err((
                        "growth.moisture_top".into(),
                        format!(
                            "face {f} has moisture {} on top and {} below: the design is written \
                             as growth_mu_top = ε⁺/moisture_top and growth_mu_bottom = \
                             ε⁻/moisture_bottom, which needs moisture on both sides of every face",
                            crate::math::human(mt),
                            crate::math::human(mb)
                        ),
                    ));
                }
                let print =
                    (c.print_thickness > 0.0).then_some(crate::rest::laws::bilayer::Print {
                        thickness: c.print_thickness,
                        modulus_ratio: c.print_modulus_ratio,
                    });
                let lambda = 1.0 + c.mu_through * 0.5 * (mt + mb);
                if !laminate.isotropic {
                    basis.push(Chain::swelling_basis(
                        &rest.abar0[f],
                        &rest.bbar0[f],
                        body.thickness[f],
                        &laminate,
                        print,
                        lambda,
                        shape,
                        d,
                    ));
                }
                ratio.push(lambda);
                shapes.push(shape);
                gel_faces.push((rest.abar0[f], rest.bbar0[f], body.thickness[f], print));
                // The strain in each layer's direction of largest swelling.
                own.extend([
                    Chain::layer_scale(top) * mt,
                    Chain::layer_scale(bottom) * mb,
                ]);
            }
            (
                Chain::Swelling {
                    basis,
                    ratio,
                    shape: shapes,
                    // Gel layers swell alike in every direction (the law refuses others), and
                    // take no through-thickness swelling.
                    gel: laminate.isotropic.then_some(crate::design::variables::Gel {
                        laminate,
                        faces: gel_faces,
                    }),
                },
                own,
            )
        }
        Variable::Thickness => {
            let law_ratio = |f: usize| body.grown_thickness.get(f).copied().unwrap_or(1.0);
            let forms = (0..nf).map(|f| (rest.abar1[f], rest.bbar1[f])).collect();
            let own = (0..nf).map(|f| body.thickness[f] * law_ratio(f)).collect();
            (
                Chain::Thickness {
                    forms,
                    reference: body.thickness.clone(),
                    law_ratio: (0..nf).map(law_ratio).collect(),
                },
                own,
            )
        }
    };
    let start = match d.start {
        Some(Start::Value(v)) => vec![v; own.len()],
        _ => own,
    };
    if let Some(i) = start.iter().position(|v| !v.is_finite()) {
        return Err((
            "design.start".into(),
            format!(
                "face {}: the scene's own design is not finite there",
                i / chain.per_face()
            ),
        ));
    }
    Ok((chain, start))
}

/// The start of `design.start = "target"`: each face's numbers fitted to the target's own
/// fundamental forms there ([`Chain::fit`], from the scene's own design `own`, within the
/// bounds): `a` of the target face's edges, `b` the mid-edge average over its neighbours (the
/// shell's own forms of the target shape). The target needs the mesh's connectivity and faces
/// of positive area.
fn fitted_start(
    path: &Path,
    target: &Mesh,
    scene: &Scene,
    d: &Design,
    chain: &Chain,
    own: &[Real],
) -> Result<Vec<Real>, DesignError> {
    same_connectivity(
        path,
        target,
        scene,
        "design.start = \"target\" fits each face's rest forms to the target's there",
    )?;
    let body = &scene.body;
    let x = &target.positions;
    let k = chain.per_face();
    let bounds = bounds(d, chain, own);
    let mut start = Vec::with_capacity(own.len());
    for (f, face) in body.mesh.faces.iter().enumerate() {
        let o = body.topo.opposite_vertex[f];
        let has = o.map(|v| v != crate::mesh::topology::NONE);
        let at = |i: usize| if has[i] { x[o[i]] } else { x[face[0]] };
        let stencil = [x[face[0]], x[face[1]], x[face[2]], at(0), at(1), at(2)];
        let forms = crate::energy::shell::face_forms(&stencil, has);
        let det = sym_det(&forms.0);
        if det.is_nan() || det <= 0.0 {
            return Err(DesignError::at(
                path,
                format!(
                    "the target's face {} has no area, so design.start = \"target\" has no \
                     metric to fit there",
                    f
                ),
            ));
        }
        let h = body.thickness[f];
        let (p, _) = chain.fit(f, &own[k * f..k * (f + 1)], &forms, h * h / 12.0, bounds);
        start.extend(p);
    }
    Ok(start)
}

/// The lower bound of a variable without `design.lower`: none, except where the law needs one:
/// a layer's stretch `1 + α ε` at least 0.5 (`|α| ≤ 1`), a thickness at least 1% of the thinnest start.
fn default_lower(v: Variable, start: &[Real]) -> Real {
    match v {
        Variable::Swelling => -0.5,
        Variable::Thickness => 0.01 * start.iter().copied().fold(Real::INFINITY, Real::min),
        _ => Real::NEG_INFINITY,
    }
}

/// The bounds on every design number: `design.lower` and `design.upper`, else the variable's
/// defaults.
fn bounds(d: &Design, chain: &Chain, start: &[Real]) -> (Real, Real) {
    (
        d.lower.unwrap_or_else(|| default_lower(d.variable, start)),
        d.upper.unwrap_or_else(|| default_upper(chain)),
    )
}

/// Checks the bounds as they apply, defaults included: lower ≤ upper, and for layer strains a
/// stretch `1 + α ε` and `1 + γ ε` that stays positive over the box on every face (the law
/// refuses a length ≤ 0). Errors: (key, why).
fn check_bounds(d: &Design, chain: &Chain, start: &[Real]) -> Result<(), (String, String)> {
    let (lo, hi) = bounds(d, chain, start);
    let h = crate::math::human;
    if lo > hi {
        // Name the bound the user gave (both are checked against each other in the file).
        let k = if d.lower.is_some() {
            "design.lower"
        } else {
            "design.upper"
        };
        return Err((
            k.into(),
            format!(
                "the lower bound {} is above the upper bound {} ({} is the default of \
                 variable = \"{}\")",
                h(lo),
                h(hi),
                if d.lower.is_some() { h(hi) } else { h(lo) },
                d.variable.name()
            ),
        ));
    }
    if let Chain::Swelling { shape, .. } = chain {
        for (f, layers) in shape.iter().enumerate() {
            for (layer, &(a, c)) in ["top", "bottom"].iter().zip(layers) {
                for (bound, e) in [("design.lower", lo), ("design.upper", hi)] {
                    let worst = (1.0 + a * e).min(1.0 + c * e);
                    if e.is_finite() && worst <= 0.0 {
                        return Err((
                            bound.into(),
                            format!(
                                "at {} the {layer} layer of face {f} would stretch by {} (its \
                                 coefficients along and across the machine direction are in \
                                 the ratio {} : {}): a length cannot become ≤ 0",
                                h(e),
                                h(worst),
                                h(a),
                                h(c)
                            ),
                        ));
                    }
                }
            }
        }
    }
    Ok(())
}

/// The upper bound of a variable without `design.upper`: none, except for a bilayer layer that
/// shrinks in one direction as it swells in the other (a negative `α` or `γ`), whose stretch
/// `1 + α ε` stays at least 0.5 with `ε ≤ 0.5`.
fn default_upper(chain: &Chain) -> Real {
    match chain {
        Chain::Swelling { shape, .. }
            if shape.iter().flatten().any(|&(a, c)| a < 0.0 || c < 0.0) =>
        {
            0.5
        }
        _ => Real::INFINITY,
    }
}

/// The Cartesian ā and b̄ of a forms design (six numbers per face), as two fields' data.
fn split_forms(p: &[Real]) -> (Vec<Real>, Vec<Real>) {
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for c in p.chunks_exact(6) {
        a.extend_from_slice(&c[..3]);
        b.extend_from_slice(&c[3..]);
    }
    (a, b)
}

/// The names and values of the design's face fields for frames (one entry per field).
fn design_fields(chain: &Chain, p: &[Real]) -> Vec<(String, Field)> {
    match chain.variable() {
        Variable::Growth => vec![("growth_factor".into(), Field::scalar(p.to_vec()))],
        Variable::Director => vec![("director_angle".into(), Field::scalar(p.to_vec()))],
        Variable::Bbar => vec![("bbar_cartesian".into(), Field::triples(p.to_vec()))],
        Variable::Swelling => {
            let (t, b): (Vec<Real>, Vec<Real>) = p.chunks_exact(2).map(|c| (c[0], c[1])).unzip();
            vec![
                ("swelling_top".into(), Field::scalar(t)),
                ("swelling_bottom".into(), Field::scalar(b)),
            ]
        }
        Variable::Thickness => vec![("rest_thickness".into(), Field::scalar(p.to_vec()))],
        Variable::Forms => {
            let (a, b) = split_forms(p);
            vec![
                ("abar_cartesian".into(), Field::triples(a)),
                ("bbar_cartesian".into(), Field::triples(b)),
            ]
        }
    }
}

/// A frame of the shape `e` at design `p`: positions aligned onto the target, the design's
/// fields, and each vertex's distance to its target point (m).
fn shape_mesh(prep: &Prepared, chain: &Chain, p: &[Real], e: &Evaluated) -> Mesh {
    let (r, t) = e.alignment;
    let positions: Vec<Vec3> = e.state.x.iter().map(|x| r * x + t).collect();
    let dist: Option<Vec<Real>> = e.nearest.as_ref().map(|near| {
        positions
            .iter()
            .zip(near)
            .map(|(x, y)| (x - y).norm())
            .collect()
    });
    let mut m = Mesh {
        positions,
        faces: prep.scene.body.input_faces(),
        face_fields: Default::default(),
        vertex_fields: Default::default(),
        source: None,
    };
    for (k, f) in design_fields(chain, p) {
        m.face_fields.insert(k, f);
    }
    if let Some(dist) = dist {
        m.vertex_fields
            .insert("target_distance".into(), Field::scalar(dist));
    }
    m
}

/// The input mesh with the fields that reproduce the design, and the settings table that
/// reads them.
fn designed(prep: &Prepared, p: &[Real]) -> (Mesh, toml::Table) {
    let mut mesh = prep.input.clone();
    let mut table = prep.settings_table.clone();
    let sub = |t: &mut toml::Table, k: &str| -> toml::Table {
        match t.remove(k) {
            Some(toml::Value::Table(x)) => x,
            _ => toml::Table::new(),
        }
    };
    match &prep.chain {
        Chain::Growth { .. } => {
            mesh.face_fields
                .insert("growth_factor".into(), Field::scalar(p.to_vec()));
            let mut g = sub(&mut table, "growth");
            g.remove("s");
            table.insert("growth".into(), toml::Value::Table(g));
        }
        Chain::Director { stretch, .. } => {
            let data = p
                .iter()
                .zip(stretch)
                .flat_map(|(th, (l, n))| [*th, *l, *n])
                .collect();
            mesh.face_fields.insert(
                "abar_info".into(),
                Field {
                    components: 3,
                    data,
                },
            );
            let mut r = sub(&mut table, "rest");
            r.remove("lce");
            r.insert("target".into(), "lce".into());
            table.insert("rest".into(), toml::Value::Table(r));
        }
        Chain::Forms { .. } => {
            let (a, b) = split_forms(p);
            mesh.face_fields
                .insert("abar_info".into(), Field::triples(a));
            mesh.face_fields
                .insert("bbar_info".into(), Field::triples(b));
            let mut r = sub(&mut table, "rest");
            r.remove("abar");
            r.remove("bbar");
            r.insert("target".into(), "mesh".into());
            table.insert("rest".into(), toml::Value::Table(r));
        }
        Chain::Bbar { frames, abar } => {
            let a = abar
                .iter()
                .zip(frames)
                .flat_map(|(a, t)| {
                    let c = push_forward(t, a);
                    [c[0], c[1], c[2]]
                })
                .collect();
            mesh.face_fields
                .insert("abar_info".into(), Field::triples(a));
            mesh.face_fields
                .insert("bbar_info".into(), Field::triples(p.to_vec()));
            let mut r = sub(&mut table, "rest");
            r.remove("abar");
            r.remove("bbar");
            r.insert("target".into(), "mesh".into());
            table.insert("rest".into(), toml::Value::Table(r));
        }
        Chain::Swelling { shape, .. } => {
            // The strains as the law's face coefficients over the scene's own moisture (the
            // face fields take precedence over [growth]'s and the regions' coefficients).
            let g = &prep.scene.body.growth;
            let mut fields: [Vec<Real>; 4] = Default::default();
            for (f, c) in p.chunks_exact(2).enumerate() {
                let [(at, ct), (ab, cb)] = shape[f];
                let (mt, mb) = (g.moisture_top[f], g.moisture_bottom[f]);
                fields[0].push(c[0] * at / mt);
                fields[1].push(c[1] * ab / mb);
                fields[2].push(c[0] * ct / mt);
                fields[3].push(c[1] * cb / mb);
            }
            // The coefficients across too when any layer is anisotropic, or when the scene gives
            // them anywhere ([growth], a region, a face field), which the written fields must
            // then replace on every face.
            let anisotropic =
                shape.iter().any(|s| s[0].0 != s[0].1 || s[1].0 != s[1].1) || g.gives_across();
            let names = [
                "growth_mu_top",
                "growth_mu_bottom",
                "growth_mu_top_perp",
                "growth_mu_bottom_perp",
            ];
            for (name, v) in names
                .into_iter()
                .zip(fields)
                .take(if anisotropic { 4 } else { 2 })
            {
                mesh.face_fields.insert(name.into(), Field::scalar(v));
            }
        }
        Chain::Thickness { .. } => {
            // The reference thickness the law scales into the designed one.
            let body = &prep.scene.body;
            let h = p
                .iter()
                .enumerate()
                .map(|(f, v)| v / body.grown_thickness.get(f).copied().unwrap_or(1.0))
                .collect();
            mesh.face_fields
                .insert("ref_thicknesses".into(), Field::scalar(h));
        }
    }
    // The thickness a growth law grows is the law's own: the mesh's thickness stays.
    (mesh, table)
}

/// One row of `design_log.csv`.
struct Row {
    iteration: usize,
    objective: Real,
    distance: Real,
    mean: Real,
    gauss: Real,
    smoothness: Real,
    gradient: Real,
    step: Real,
    trials: usize,
    timing: DesignTiming,
    wall: f64,
}

const LOG_HEADER: &str = "iteration,objective,distance,distance_m,mean_curvature_error,\
                          gauss_curvature_error,smoothness,projected_gradient,step,trials,\
                          evaluations,refused,newton_iterations,wall_seconds\n";

impl Row {
    fn csv(&self, size: Real) -> String {
        let t = &self.timing;
        format!(
            "{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{},{},{},{:.3}\n",
            self.iteration,
            self.objective,
            self.distance,
            self.distance * size,
            self.mean,
            self.gauss,
            self.smoothness,
            self.gradient,
            self.step,
            self.trials,
            t.evaluations,
            t.refused,
            t.newton_iterations,
            self.wall
        )
    }
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), DesignError> {
    write_atomic(path, bytes).map_err(|e| DesignError::at(path, format!("cannot write: {e}")))
}

/// The files of an earlier design in `out`.
const OUTPUTS: [&str; 6] = [
    "design_summary.json",
    "design_log.csv",
    "designed.vtk",
    "settings.toml",
    "shape.vtk",
    "iterations.pvd",
];

/// Designs: `prepare`d input, the optimiser, and the files. `Ok` with the outcome (converged
/// or not); `Err` for bad input or a failed write.
pub fn run(req: &Request) -> Result<Outcome, DesignError> {
    let clock = Instant::now();
    let prep = prepare(req)?;
    if !req.overwrite {
        if let Some(f) = OUTPUTS.iter().find(|f| req.out.join(f).exists()) {
            return Err(DesignError::at(
                &req.out,
                format!("holds an earlier design ({f}); give --overwrite to replace it"),
            ));
        }
    }
    let frames_dir = req.out.join("iterations");
    std::fs::create_dir_all(&frames_dir)
        .map_err(|e| DesignError::at(&frames_dir, format!("cannot create: {e}")))?;
    let body = &prep.scene.body;
    let topo = Topology::build(&body.mesh).map_err(|e| DesignError(e.to_string()))?;
    let d = &prep.design;
    let size = bounding_diagonal(&prep.target.positions);
    let distance = (d.distance_weight > 0.0).then(|| {
        let term = match d.objective {
            Objective::Points => DistanceTerm::Points(Points::new(
                &body.mesh,
                prep.target.positions.clone(),
                d.align,
            )),
            Objective::Surface => DistanceTerm::Surface(Box::new(Surface::new(
                &body.mesh,
                &prep.target.positions,
                &prep.target.faces,
                d.align,
            ))),
        };
        (d.distance_weight, term)
    });
    let (mean, gauss) = prep.curvature_targets.clone();
    let curvature = (mean.is_some() || gauss.is_some()).then(|| {
        Curvature::new(
            &body.mesh,
            &topo,
            size,
            mean.map(|m| (d.mean_curvature_weight, m)),
            gauss.map(|g| (d.gauss_curvature_weight, g)),
        )
    });
    let shape = Shape {
        distance,
        curvature,
    };
    let scale = match d.variable {
        Variable::Forms => vec![1.0, 1.0, 1.0, size, size, size],
        Variable::Bbar => vec![size, size, size],
        Variable::Swelling => vec![1.0, 1.0],
        Variable::Thickness => {
            // Thickness differences relative to the mean thickness.
            let mean = prep.start.iter().sum::<Real>() / prep.start.len().max(1) as Real;
            vec![1.0 / mean]
        }
        _ => vec![1.0],
    };
    let smooth = Smoothness::new(
        &body.mesh,
        &topo,
        d.smoothness,
        d.variable == Variable::Director,
        scale,
    );
    let chain = prep.chain.clone();
    let mut problem =
        Problem::new(&prep.scene, chain.clone(), shape, smooth).map_err(DesignError)?;
    if d.smoothing_length > 0.0 {
        problem.metric = Some(Sobolev::new(
            &body.mesh,
            &topo,
            d.smoothing_length * size,
            chain.per_face(),
        ));
    }
    let (lower, upper) = bounds(d, &prep.chain, &prep.start);
    let opts = Options {
        memory: d.memory,
        max_iterations: d.max_iterations,
        tolerance: d.tolerance,
        first_step: d.first_step,
        lower,
        upper,
    };
    let mut log = String::from(LOG_HEADER);
    let mut series: Vec<(Real, String)> = Vec::new();
    let mut io_error: Option<DesignError> = None;
    let every = d.frames_every;
    // The iterations before the current round, the last iteration reported, the forward
    // checks made and the last one.
    let (mut offset, mut last_iteration, mut rounds) = (0usize, 0usize, 0usize);
    let mut check: Option<ForwardCheck> = None;
    let mut from = prep.start.clone();
    let result = loop {
        let round_opts = Options {
            max_iterations: d.max_iterations.saturating_sub(offset).max(1),
            ..opts.clone()
        };
        let round = {
            let mut report = |it: &Iterate, prob: &Problem| -> Option<String> {
                let e = prob.current.as_ref()?;
                let iteration = it.iteration + offset;
                last_iteration = iteration;
                let distance = Points::relative_rms(e.distance);
                let row = Row {
                    iteration,
                    objective: it.value,
                    distance,
                    mean: Points::relative_rms(e.mean),
                    gauss: Points::relative_rms(e.gauss),
                    smoothness: e.smoothness,
                    gradient: it.gradient,
                    step: it.step,
                    trials: it.trials,
                    timing: prob.timing,
                    wall: clock.elapsed().as_secs_f64(),
                };
                log.push_str(&row.csv(size));
                if !req.quiet {
                    eprintln!(
                        "design: iteration {iteration}, distance {} of the target's size, \
                         objective {}, {:.1} s",
                        crate::math::human(distance),
                        crate::math::human(it.value),
                        row.wall
                    );
                }
                if (every > 0 && iteration.is_multiple_of(every)) || it.iteration == 0 {
                    let name = format!("iteration_{iteration:05}.vtk");
                    let m = shape_mesh(&prep, &chain, it.p, e);
                    if let Err(err) =
                        write_mesh(&frames_dir.join(&name), &m, Format::Vtk, "shellsim design")
                    {
                        io_error = Some(DesignError(err.to_string()));
                        return Some("output failed".into());
                    }
                    series.push((iteration as Real, format!("iterations/{name}")));
                }
                (d.target_distance > 0.0 && distance <= d.target_distance).then(|| {
                    format!(
                        "the distance to the target, {} of its size, is within \
                         design.target_distance",
                        crate::math::human(distance)
                    )
                })
            };
            match d.method {
                Method::Lbfgs => minimise(&mut problem, from.clone(), &round_opts, &mut report),
                Method::GaussNewton => super::gauss_newton::minimise(
                    &mut problem,
                    from.clone(),
                    &round_opts,
                    &mut report,
                ),
            }
        };
        let Ok((stop, p, value)) = round else {
            break round;
        };
        if io_error.is_some() || !d.forward_check {
            break Ok((stop, p, value));
        }
        // The written design, run forward as `shellsim settings.toml designed.vtk` runs it.
        let mut c = forward_check(&prep, &problem, &p);
        rounds += 1;
        c.rounds = rounds;
        let far = |c: &ForwardCheck| {
            c.distance
                .is_none_or(|x| d.target_distance == 0.0 || x > d.target_distance)
        };
        let again = !c.reproduces
            && far(&c)
            && rounds < FORWARD_ROUNDS
            && stop != Stop::Limit
            && last_iteration + 1 < d.max_iterations;
        if again {
            if let Some(state) = c.state.take() {
                let restarted = problem.restart_from(&p, state);
                if let Err(e) = &restarted {
                    c.restart = Some(e.clone());
                }
                if restarted.is_ok() {
                    if !req.quiet {
                        eprintln!(
                            "design: the forward run of the design found another equilibrium, \
                             {} of the size from the designed one; designing on from it",
                            crate::math::human(c.offset.unwrap_or(0.0))
                        );
                    }
                    offset = last_iteration + 1;
                    from = p;
                    check = Some(c);
                    continue;
                }
            }
        }
        check = Some(c);
        break Ok((stop, p, value));
    };
    if let Some(e) = io_error {
        return Err(e);
    }
    let (stop, p, value) = result.map_err(|e| {
        DesignError(format!(
            "{}: the starting design has no equilibrium: {e}",
            req.design.display()
        ))
    })?;
    let e = problem
        .current
        .clone()
        .ok_or_else(|| DesignError("no design was evaluated".into()))?;
    let iterations = last_iteration;
    let (mut converged, mut reason) = match &stop {
        Stop::Converged(w) => (true, w.clone()),
        Stop::Stalled(w) => (false, format!("the design cannot improve: {w}")),
        Stop::Limit => (
            false,
            format!("design.max_iterations ({}) reached", d.max_iterations),
        ),
    };
    if let Some(c) = &check {
        if let Some(why) = c.failure(d.target_distance) {
            converged = false;
            reason = format!("{reason}; but {why}");
        }
    }
    // The last iteration's frame, when `frames_every` skipped it.
    let last = format!("iterations/iteration_{iterations:05}.vtk");
    if series.last().map(|s| &s.1) != Some(&last) {
        let m = shape_mesh(&prep, &chain, &p, &e);
        write_mesh(&req.out.join(&last), &m, Format::Vtk, "shellsim design")
            .map_err(|e| DesignError(e.to_string()))?;
        series.push((iterations as Real, last));
    }
    write(
        &req.out.join("iterations.pvd"),
        series_xml(&series).as_bytes(),
    )?;
    write(&req.out.join("design_log.csv"), log.as_bytes())?;
    let shape = shape_mesh(&prep, &chain, &p, &e);
    write_mesh(
        &req.out.join("shape.vtk"),
        &shape,
        Format::Vtk,
        "shellsim design",
    )
    .map_err(|e| DesignError(e.to_string()))?;
    let (mesh, table) = designed(&prep, &p);
    write_mesh(
        &req.out.join("designed.vtk"),
        &mesh,
        Format::Vtk,
        "shellsim design",
    )
    .map_err(|e| DesignError(e.to_string()))?;
    let settings = format!(
        "# The scene of {} with the design of `shellsim design` as mesh fields: run it with\n\
         # shellsim settings.toml designed.vtk\n{}",
        req.design.display(),
        toml::to_string(&table).map_err(|e| DesignError(e.to_string()))?
    );
    write(&req.out.join("settings.toml"), settings.as_bytes())?;
    let distance = Points::relative_rms(e.distance);
    let t = problem.timing;
    let per_newton = if t.newton_iterations > 0 {
        t.equilibrium / t.newton_iterations as f64
    } else {
        0.0
    };
    let per_adjoint = (t.adjoint + t.sensitivities) / t.evaluations.max(1) as f64;
    let summary = serde_json::json!({
        "converged": converged,
        "reason": reason,
        "variable": d.variable.name(),
        "faces": body.num_faces(),
        "design_numbers": p.len(),
        "iterations": iterations,
        "objective": finite(value),
        "distance": finite(distance),
        "distance_m": finite(distance * size),
        "target_size_m": finite(size),
        "mean_curvature_error": finite(Points::relative_rms(e.mean)),
        "gauss_curvature_error": finite(Points::relative_rms(e.gauss)),
        "smoothness": finite(e.smoothness),
        "forward_check": check.as_ref().map_or(serde_json::json!(false), ForwardCheck::json),
        "evaluations": t.evaluations,
        "refused_evaluations": t.refused,
        "newton_iterations": t.newton_iterations,
        "wall_seconds": clock.elapsed().as_secs_f64(),
        "timing": {
            "equilibrium": t.equilibrium,
            "adjoint": t.adjoint,
            "sensitivities": t.sensitivities,
            "seconds_per_newton_iteration": per_newton,
            "seconds_per_gradient": per_adjoint,
            "gradient_over_newton_iteration": if per_newton > 0.0 { per_adjoint / per_newton } else { 0.0 },
        },
    });
    let text = serde_json::to_string_pretty(&summary).map_err(|e| DesignError(e.to_string()))?;
    write(&req.out.join("design_summary.json"), text.as_bytes())?;
    Ok(Outcome {
        converged,
        reason,
        iterations,
        objective: value,
        distance,
    })
}

/// The most forward checks of one design: after each but the last, a design whose forward run
/// finds another equilibrium goes on from that one.
const FORWARD_ROUNDS: usize = 3;

/// A forward run's equilibrium within this much of the designed one (RMS over the size, after
/// alignment) is the designed one: the solver's own tolerance is far below.
const REPRODUCES: Real = 1e-5;

/// What the forward run of a written design found.
struct ForwardCheck {
    /// Whether it ends on the designed equilibrium (within [`REPRODUCES`]).
    reproduces: bool,
    /// Its distance to the target, over the target's size (with a distance term).
    distance: Option<Real>,
    /// Its distance from the designed equilibrium, over the size.
    offset: Option<Real>,
    /// Why it failed, when it did.
    error: Option<String>,
    /// Its equilibrium.
    state: Option<crate::solve::State>,
    /// The checks made so far.
    rounds: usize,
    /// Why the design could not go on from the forward run's equilibrium, when it could not.
    restart: Option<String>,
}

impl ForwardCheck {
    /// Its record in the summary (the keys without a value left out: no nulls).
    fn json(&self) -> serde_json::Value {
        let mut m = serde_json::Map::new();
        m.insert("reproduces".into(), self.reproduces.into());
        m.insert("rounds".into(), self.rounds.into());
        if let Some(x) = self.distance {
            m.insert("distance".into(), finite(x).into());
        }
        if let Some(x) = self.offset {
            m.insert("offset_from_designed".into(), finite(x).into());
        }
        if let Some(e) = &self.error {
            m.insert("error".into(), e.clone().into());
        }
        if let Some(e) = &self.restart {
            m.insert("restart_error".into(), e.clone().into());
        }
        serde_json::Value::Object(m)
    }

    /// Why the design does not stand, if it does not: the forward run failed, or ended on
    /// another equilibrium that is not within `target_distance` (when set) of the target.
    fn failure(&self, target_distance: Real) -> Option<String> {
        if let Some(e) = &self.error {
            return Some(format!("the forward run of the written design failed: {e}"));
        }
        if self.reproduces {
            return None;
        }
        let distance = self.distance.unwrap_or(Real::INFINITY);
        if target_distance > 0.0 && distance <= target_distance {
            return None;
        }
        let restart = self
            .restart
            .as_ref()
            .map(|e| format!(" (the design could not go on from it: {e})"))
            .unwrap_or_default();
        Some(format!(
            "the written design run forward from the mesh (`shellsim settings.toml designed.vtk`) \
             ends on another equilibrium, {} of the size from the designed one and {} from the \
             target{restart}",
            crate::math::human(self.offset.unwrap_or(0.0)),
            crate::math::human(distance)
        ))
    }
}

/// The sink of a forward check: keeps the last frame's state, writes nothing.
#[derive(Default)]
struct LastFrame {
    state: Option<crate::solve::State>,
    frames: usize,
    faces: usize,
}

impl crate::integrate::Sink for LastFrame {
    fn frame(
        &mut self,
        _: &crate::energy::Potential,
        state: &crate::solve::State,
        _: &[Vec3],
        _: crate::integrate::report::LogRow,
        _: Option<&crate::integrate::DriverState>,
    ) -> Result<(), crate::integrate::OutputError> {
        self.state = Some(state.clone());
        self.frames += 1;
        Ok(())
    }
    fn set_face_field(&mut self, _: &str, _: Vec<Real>) {}
    fn num_faces(&self) -> usize {
        self.faces
    }
    fn num_frames(&self) -> usize {
        self.frames
    }
    fn last_frame(&self) -> String {
        String::new()
    }
    fn release_reserve(&mut self) {}
    fn summary(&self, _: &crate::integrate::Summary) -> Result<(), crate::integrate::OutputError> {
        Ok(())
    }
}

/// Runs the written design of `p` forward, as `shellsim settings.toml designed.vtk` would (the
/// designed mesh and settings, from the flat sheet, on the design's thread count), and compares
/// its equilibrium with the designed one (`problem`'s current) and with the target.
fn forward_check(prep: &Prepared, problem: &Problem, p: &[Real]) -> ForwardCheck {
    let mut c = ForwardCheck {
        reproduces: false,
        distance: None,
        offset: None,
        error: None,
        state: None,
        rounds: 0,
        restart: None,
    };
    let run = || -> Result<crate::solve::State, String> {
        let (mesh, table) = designed(prep, p);
        let text = toml::to_string(&table).map_err(|e| e.to_string())?;
        let settings =
            Settings::from_str_with(&text, "the designed scene", &[]).map_err(|e| e.to_string())?;
        let faces = mesh.faces.len();
        let scene = Scene::build(mesh, settings).map_err(|e| e.to_string())?;
        let mut sink = LastFrame {
            faces,
            ..LastFrame::default()
        };
        let summary = crate::integrate::run(
            &scene,
            &mut sink,
            &mut crate::integrate::Quiet,
            rayon::current_num_threads(),
            None,
        )
        .map_err(|e| e.to_string())?;
        if !summary.converged {
            return Err(summary.reason);
        }
        sink.state.ok_or_else(|| "it wrote no frame".to_string())
    };
    let state = match run() {
        Ok(s) => s,
        Err(e) => {
            c.error = Some(e);
            return c;
        }
    };
    let seen = problem.shape.eval(&state.x);
    if problem.shape.distance.is_some() {
        c.distance = Some(Points::relative_rms(seen.distance));
    }
    if let Some(e) = &problem.current {
        let mesh = &prep.scene.body.mesh;
        let designed = Points::new(mesh, e.state.x.clone(), true);
        let offset = Points::relative_rms(designed.eval(&state.x).value);
        c.offset = Some(offset);
        c.reproduces = offset <= REPRODUCES;
    }
    c.state = Some(state);
    c
}

/// A number for the summary: finite values as they are, anything else as 0 (never NaN).
fn finite(x: Real) -> Real {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}
