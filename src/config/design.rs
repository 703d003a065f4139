//! `[design]`: inverse design (`shellsim design DESIGN.toml MESH TARGET`): which per-face
//! rest-form variable is designed, its bounds and smoothness, the objective and the optimiser's
//! controls. The rest of a design file is an ordinary settings file: the scene every design
//! iterate is solved in.

use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// The designed variable, one or more numbers per face.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Variable {
    /// The conformal growth factor `s` of the isotropic growth law in `growth.law`
    /// (`isotropic`, `isotropic_in_plane` or `isotropic_metric_only`), dimensionless.
    #[default]
    Growth,
    /// The liquid-crystal director angle θ (rad, from the reference x axis), with the stretch
    /// λ and ratio ν of `[rest.lce]` (or of the mesh's `abar_info`) kept.
    Director,
    /// The rest forms themselves: ā (dimensionless) and b̄ (1/m) in reference Cartesian
    /// coordinates, `[xx, xy, yy]` each, six numbers per face.
    Forms,
    /// The rest second fundamental form b̄ alone (1/m, reference Cartesian `[xx, xy, yy]`,
    /// three numbers per face), with the scene's own ā kept.
    Bbar,
    /// The in-plane strains `ε⁺`, `ε⁻` of the top and bottom layers of `growth.law =
    /// "bilayer"` (dimensionless, two numbers per face: the stretches are `1 + ε±`).
    Swelling,
    /// The rest thickness h̄ (m), with the scene's own rest forms.
    Thickness,
}

impl Variable {
    /// The settings name.
    pub fn name(self) -> &'static str {
        match self {
            Variable::Growth => "growth",
            Variable::Director => "director",
            Variable::Forms => "forms",
            Variable::Bbar => "bbar",
            Variable::Swelling => "swelling",
            Variable::Thickness => "thickness",
        }
    }
}

/// What the objective measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// Point to point: the target has the design mesh's connectivity; each vertex is compared
    /// with its own.
    #[default]
    Points,
    /// Surface to surface: the target is any triangle mesh; each point of either surface is
    /// compared with its closest point on the other.
    Surface,
}

impl Objective {
    /// The settings name.
    pub fn name(self) -> &'static str {
        match self {
            Objective::Points => "points",
            Objective::Surface => "surface",
        }
    }
}

/// The optimiser.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Projected L-BFGS on the objective's gradient.
    #[default]
    Lbfgs,
    /// Damped Gauss–Newton on the distance term's least squares, through the equilibrium's
    /// linear response.
    GaussNewton,
}

/// Where a design starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Start {
    /// This value for every designed number (the variable's unit).
    Value(Real),
    /// Each face's numbers fitted to the target's own fundamental forms there (the target has
    /// the mesh's connectivity).
    Target,
}

impl Serialize for Start {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Start::Value(v) => s.serialize_f64(*v),
            Start::Target => s.serialize_str("target"),
        }
    }
}

impl<'de> Deserialize<'de> for Start {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Start;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or \"target\"")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Start, E> {
                Ok(Start::Value(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Start, E> {
                Ok(Start::Value(v as Real))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Start, E> {
                Ok(Start::Value(v as Real))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Start, E> {
                match v {
                    "target" => Ok(Start::Target),
                    _ => Err(E::custom(format!(
                        "expected a number or \"target\", got \"{v}\""
                    ))),
                }
            }
        }
        d.deserialize_any(V)
    }
}

/// The `[design]` section.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Design {
    /// The designed variable: `"growth"` (default), `"director"` or `"forms"`.
    pub variable: Variable,
    /// The lower bound on every designed number (the variable's unit; default: none).
    pub lower: Option<Real>,
    /// The upper bound (default: none).
    pub upper: Option<Real>,
    /// Where the design starts: the scene's own design by default (its growth factor,
    /// director or rest forms), a value everywhere (the variable's unit), or `"target"`: each
    /// face's numbers fitted to the target's own fundamental forms.
    pub start: Option<Start>,
    /// Weight of the smoothness term `w/2 Σ_edges (|e|/d) Δp²` (the discrete `∫|∇p|² dA`
    /// of the piecewise-constant design; dimensionless; default 0).
    pub smoothness: Real,
    /// The smoothing length ℓ of the optimiser's steps, over the target's size: steps follow
    /// the Sobolev gradient `(A + ℓ² K)⁻¹ ∇J`, smooth over ℓ, which keeps a thin sheet from
    /// crumpling on the way (default 0.05; 0: the plain per-face gradient). It changes the
    /// path, not the optimum.
    pub smoothing_length: Real,
    /// How the distance to the target is measured: `"points"` (default; the target has the
    /// mesh's connectivity) or `"surface"` (any target mesh).
    pub objective: Objective,
    /// Weight of the distance term (default 1; 0: no distance term).
    pub distance_weight: Real,
    /// Weight of the mean curvature term `½ Σ w_f (H − H*)² L²` (default 0: none).
    pub mean_curvature_weight: Real,
    /// Weight of the Gauss curvature term `½ Σ w_f (K − K*)² L⁴` (default 0: none).
    pub gauss_curvature_weight: Real,
    /// Whether the shape is compared after the best rigid motion (default: true).
    pub align: bool,
    /// The most design iterations (default 200).
    pub max_iterations: usize,
    /// Stop when the objective changes by less than this, relative, over one iteration
    /// (default 1e-9).
    pub tolerance: Real,
    /// Stop when the RMS distance to the target, over the target's size, is below this
    /// (default 0: off).
    pub target_distance: Real,
    /// The largest change of a designed number in the first iteration (the variable's unit,
    /// default 0.1); later steps are sized by the quasi-Newton model.
    pub first_step: Real,
    /// Run the written design forward (as `shellsim settings.toml designed.vtk` does) when the
    /// optimiser stops; when it ends on another equilibrium, design on from that one (up to
    /// three checks in all), and report the forward run's distance (default true).
    pub forward_check: bool,
    /// The optimiser: `"lbfgs"` (default) or `"gauss_newton"` (needs a distance term).
    pub method: Method,
    /// The quasi-Newton memory: pairs kept by L-BFGS (default 10).
    pub memory: usize,
    /// A frame of the shape every this many iterations (default 1; 0: the first and last only).
    pub frames_every: usize,
}

impl Default for Design {
    fn default() -> Self {
        Design {
            variable: Variable::Growth,
            lower: None,
            upper: None,
            start: None,
            smoothness: 0.0,
            smoothing_length: 0.05,
            objective: Objective::Points,
            distance_weight: 1.0,
            mean_curvature_weight: 0.0,
            gauss_curvature_weight: 0.0,
            align: true,
            max_iterations: 200,
            tolerance: 1e-9,
            target_distance: 0.0,
            first_step: 0.1,
            method: Method::Lbfgs,
            forward_check: true,
            memory: 10,
            frames_every: 1,
        }
    }
}

/// The most design iterations accepted.
pub const MAX_ITERATIONS: usize = 100_000;

impl Design {
    /// Validates `[design]`: finite bounds with lower ≤ upper, a start within them, positive
    /// step, tolerance and memory.
    pub fn validate(&self) -> Result<(), Invalid> {
        let ck = Check;
        for (k, v) in [
            ("design.lower", self.lower),
            ("design.upper", self.upper),
            (
                "design.start",
                match self.start {
                    Some(Start::Value(v)) => Some(v),
                    _ => None,
                },
            ),
        ] {
            if let Some(v) = v {
                if !v.is_finite() {
                    return ck.inv(
                        k,
                        format!("must be a finite number, got {}", crate::math::human(v)),
                    );
                }
            }
        }
        if let (Some(lo), Some(hi)) = (self.lower, self.upper) {
            if lo > hi {
                return ck.inv(
                    "design.lower",
                    format!(
                        "the lower bound {} is above the upper bound {}",
                        crate::math::human(lo),
                        crate::math::human(hi)
                    ),
                );
            }
        }
        if let Some(Start::Value(s)) = self.start {
            if self.lower.is_some_and(|lo| s < lo) || self.upper.is_some_and(|hi| s > hi) {
                return ck.inv(
                    "design.start",
                    format!("{} is outside the bounds", crate::math::human(s)),
                );
            }
        }
        if self.start == Some(Start::Target) && self.variable == Variable::Thickness {
            return ck.inv(
                "design.start",
                "\"target\" fits each face's rest forms to the target's, and a designed \
                 thickness does not change them: give a thickness (m) or leave the scene's own"
                    .into(),
            );
        }
        if matches!(self.variable, Variable::Forms | Variable::Bbar)
            && (self.lower.is_some() || self.upper.is_some())
        {
            return ck.inv(
                "design.lower",
                "bounds apply to a growth factor or a director angle; rest forms have none (their \
                 metric must stay positive definite, which the design keeps)"
                    .into(),
            );
        }
        if self.variable == Variable::Thickness && self.lower.is_some_and(|l| l <= 0.0) {
            return ck.inv(
                "design.lower",
                "a designed thickness must stay positive: give a positive lower bound (m)".into(),
            );
        }
        if self.variable == Variable::Swelling && self.lower.is_some_and(|l| l <= -1.0) {
            return ck.inv(
                "design.lower",
                "a layer's stretch 1 + ε must stay positive: give a lower bound above −1".into(),
            );
        }
        ck.nonneg("design.smoothness", self.smoothness)?;
        ck.nonneg("design.distance_weight", self.distance_weight)?;
        ck.nonneg("design.mean_curvature_weight", self.mean_curvature_weight)?;
        ck.nonneg("design.gauss_curvature_weight", self.gauss_curvature_weight)?;
        if self.distance_weight + self.mean_curvature_weight + self.gauss_curvature_weight <= 0.0 {
            return ck.inv(
                "design.distance_weight",
                "the objective has no term: give design.distance_weight, \
                 design.mean_curvature_weight or design.gauss_curvature_weight a positive weight"
                    .into(),
            );
        }
        ck.nonneg("design.smoothing_length", self.smoothing_length)?;
        ck.pos("design.tolerance", self.tolerance)?;
        ck.nonneg("design.target_distance", self.target_distance)?;
        if self.target_distance > 0.0 && self.distance_weight == 0.0 {
            return ck.inv(
                "design.target_distance",
                "stops on the distance to the target, which this objective does not have \
                 (design.distance_weight = 0)"
                    .into(),
            );
        }
        if self.method == Method::GaussNewton && self.distance_weight == 0.0 {
            return ck.inv(
                "design.method",
                "\"gauss_newton\" models the distance term's least squares, which this \
                 objective does not have (design.distance_weight = 0): use \"lbfgs\""
                    .into(),
            );
        }
        ck.pos("design.first_step", self.first_step)?;
        if self.memory == 0 || self.memory > 100 {
            return ck.inv(
                "design.memory",
                format!("must be 1 to 100, got {}", self.memory),
            );
        }
        if self.max_iterations == 0 || self.max_iterations > MAX_ITERATIONS {
            return ck.inv(
                "design.max_iterations",
                format!("must be 1 to {MAX_ITERATIONS}, got {}", self.max_iterations),
            );
        }
        Ok(())
    }
}

/// The `[design]` section of a design file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DesignFile {
    #[serde(default)]
    design: Design,
}

/// The table header a line opens (`[name]` or `[[name]]`, with an optional comment), if any.
fn header(line: &str) -> Option<&str> {
    let t = line.trim_start();
    let body = t.strip_prefix("[[").or_else(|| t.strip_prefix('['))?;
    let end = body.find(']')?;
    let name = body[..end].trim();
    let rest = body[end..].trim_start_matches(']').trim();
    let keyish = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '"' | ' '));
    (keyish && (rest.is_empty() || rest.starts_with('#'))).then_some(name)
}

/// Splits a design file into its settings part and its `[design]` part (the `[design]` and
/// `[design.*]` tables), each the whole file with the other's lines blanked, so that both
/// parsers' line numbers are the file's.
pub fn split(text: &str) -> (String, String) {
    let (mut settings, mut design) = (String::new(), String::new());
    let mut inside = false;
    for line in text.lines() {
        if let Some(name) = header(line) {
            let name = name.trim_matches('"');
            inside = name == "design" || name.starts_with("design.");
        }
        let (to, blank) = if inside {
            (&mut design, &mut settings)
        } else {
            (&mut settings, &mut design)
        };
        to.push_str(line);
        to.push('\n');
        blank.push('\n');
    }
    (settings, design)
}

/// Whether a settings text is a design file: it has a `[design]` (or `[design.*]`) table.
pub fn is_design_file(text: &str) -> bool {
    !split(text).1.trim().is_empty()
}

/// Parses and validates the `[design]` part of a design file (from [`split`]). The error is the
/// message to print after the file's name: the TOML parser's (with its line and key) or the
/// invalid key's.
pub fn parse(design_part: &str) -> Result<Design, String> {
    let file: DesignFile = toml::from_str(design_part).map_err(|e| e.to_string())?;
    file.design
        .validate()
        .map_err(|e| format!("invalid '{}': {}", e.key, e.reason))?;
    Ok(file.design)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_design_file_splits_into_its_parts_keeping_line_numbers() {
        let text = "[material]\nyoung = 1.0\nfix = [\n  [0.1, 0.2],\n]\n[design]\nvariable = \"director\"\n\
                    smoothness = 0.5 # w\n[solver]\nmode = \"static\"\n";
        let (s, d) = split(text);
        assert_eq!(s.lines().count(), text.lines().count());
        assert_eq!(d.lines().count(), text.lines().count());
        assert!(s.contains("[0.1, 0.2]") && s.contains("[solver]") && !s.contains("director"));
        let design = parse(&d).unwrap();
        assert_eq!(design.variable, Variable::Director);
        assert_eq!(design.smoothness, 0.5);
        let e = parse("[design]\n\nvariabel = 1\n").unwrap_err();
        assert!(e.contains("line 3") && e.contains("variabel"), "{e}");
        let e = parse("[design]\nlower = 2.0\nupper = 1.0\n").unwrap_err();
        assert!(e.contains("design.lower"), "{e}");
    }

    #[test]
    fn bounds_with_lower_above_upper_are_refused() {
        let d = Design {
            lower: Some(1.0),
            upper: Some(-1.0),
            ..Default::default()
        };
        let e = d.validate().unwrap_err();
        assert_eq!(e.key, "design.lower");
        assert!(e.reason.contains("above the upper bound"), "{}", e.reason);
        assert!(Design::default().validate().is_ok());
    }

    #[test]
    fn a_start_outside_the_bounds_is_refused() {
        let d = Design {
            lower: Some(-0.5),
            upper: Some(0.5),
            start: Some(Start::Value(0.7)),
            ..Default::default()
        };
        assert_eq!(d.validate().unwrap_err().key, "design.start");
    }

    #[test]
    fn a_start_is_a_number_or_the_target() {
        let d = parse("[design]\nstart = 0.25\n").unwrap();
        assert_eq!(d.start, Some(Start::Value(0.25)));
        let d = parse("[design]\nstart = -1\n").unwrap();
        assert_eq!(d.start, Some(Start::Value(-1.0)));
        let d = parse("[design]\nstart = \"target\"\n").unwrap();
        assert_eq!(d.start, Some(Start::Target));
        let e = parse("[design]\nstart = \"flat\"\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("design.start") || e.contains("start"), "{e}");
        assert!(e.contains("\"target\""), "{e}");
        let e = parse("[design]\nvariable = \"thickness\"\nstart = \"target\"\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("design.start"), "{e}");
    }
}
