//! MorphoShell's settings files (`name = value;` statements, `//` comments), converted into a
//! shellsim settings file with the same physics.
//!
//! MorphoShell reads its settings by position (its `read_settings.cpp`): after the comments
//! (`//` to the end of the line) and all white space are removed, the n-th statement must carry
//! the n-th name of [`ENTRIES`], and all 23 must be there. The two switches are `true` or
//! `false`, the gradient-descent step count an integer, the rest numbers. The importer keeps
//! those rules and names the line and the entry expected when one is broken, and refuses
//! entries after the last (MorphoShell would ignore them). It also reads the gravity layout
//! ([`GRAVITY_ENTRIES`], 24 entries with `grav_field_strength`), which its second entry tells
//! apart.
//!
//! The translation (MorphoShell's meaning → shellsim's key):
//! * its stretching convention (strain `a − ā`, 4× the Koiter energy) and its patch fit:
//!   `material.stretch_convention = "morphoshell"`, `material.bending = "patch_fit"`;
//! * μ per face (`ref_shear_modulus_if_uniform` when positive; zero or negative means the
//!   mesh's `ref_shear_moduli`, as in MorphoShell): `material.young = 2μ(1+ν)`,
//!   `use_mesh_shear_modulus`; the same for the thickness. With the uniform value, the mesh's
//!   per-face field is ignored (MorphoShell's meshes carry the placeholder −1234 there);
//! * its dynamics and their prefactors: `solver.mode = "explicit"`, `[explicit]`; each dial
//!   phase between holds lasts `dial_phase_time_prefactor` long times, so
//!   `dial_long_times = prefactor / spacing`, and the holds are the multiples of the spacing
//!   below 1;
//! * its equilibrium thresholds (kept in `[explicit]`; the test used stays shellsim's, which
//!   cannot fire early; `explicit.equilibrium = "morphoshell"` reproduces MorphoShell's stop);
//! * bend stiffening γ, gravity (gravity layout), the glass slides (`slide_speed_prefactor` × L / T_bend, with L
//!   the largest sheet's reference perimeter (MorphoShell's adds up every sheet's boundary; the
//!   same for one sheet) and T_bend the bending long time, needs the mesh: given, the speed
//!   is computed; without it, a nonzero prefactor is an error that says so);
//! * `dialling_from_ansatz_rather_than_ref_state`: `dial.from = "start"`, with the ansatz given
//!   as `--restart` (MorphoShell's ansatz files are read as they are:
//!   [`crate::restart::read_ansatz`]).

use crate::math::Real;
use anyhow::{bail, Result};

/// MorphoShell's 23 entries, in the order its `read_settings.cpp` reads them.
pub const ENTRIES: [&str; 23] = [
    "outputs_per_char_long_time",
    "ref_thickness_if_uniform",
    "timestep_prefactor",
    "dialling_from_ansatz_rather_than_ref_state",
    "dial_factors_to_hold_at_spacing",
    "dial_phase_time_prefactor",
    "time_between_equil_checks_prefactor",
    "damping_prefactor_1",
    "damping_prefactor_2",
    "num_steps_to_use_gradient_descent_dynamics_for_before_switching_to_newtonian_dynamics",
    "force_to_char_force_ratio_equil_threshold",
    "speed_to_char_speed_ratio_equil_threshold",
    "def_poisson_ratio",
    "ref_shear_modulus_if_uniform",
    "ref_density",
    "bend_stiffening_scale_factor",
    "patch_mat_dimless_conditioning_thresh",
    "slide_stiffness_prefactor",
    "slide_friction_coefficent",
    "slide_speed_prefactor",
    "using_initial_glass_slide_z_coords_from_settings_file",
    "initial_upper_slide_z_coord",
    "initial_lower_slide_z_coord",
];

/// The gravity layout: MorphoShell's entries and `grav_field_strength`, 24 in this order. Its
/// second entry differs from MorphoShell's, so a file is read in this layout exactly when its
/// second entry is `dialling_from_ansatz_rather_than_ref_state`.
pub const GRAVITY_ENTRIES: [&str; 24] = [
    "outputs_per_char_long_time",
    "dialling_from_ansatz_rather_than_ref_state",
    "patch_mat_dimless_conditioning_thresh",
    "ref_thickness_if_uniform",
    "def_poisson_ratio",
    "ref_shear_modulus_if_uniform",
    "ref_density",
    "dial_phase_time_prefactor",
    "time_between_equil_checks_prefactor",
    "damping_prefactor_1",
    "damping_prefactor_2",
    "timestep_prefactor",
    "dial_factors_to_hold_at_spacing",
    "force_to_char_force_ratio_equil_threshold",
    "speed_to_char_speed_ratio_equil_threshold",
    "bend_stiffening_scale_factor",
    "slide_stiffness_prefactor",
    "slide_friction_coefficent",
    "slide_speed_prefactor",
    "using_initial_glass_slide_z_coords_from_settings_file",
    "initial_upper_slide_z_coord",
    "initial_lower_slide_z_coord",
    "grav_field_strength",
    "num_steps_to_use_gradient_descent_dynamics_for_before_switching_to_newtonian_dynamics",
];

/// The entries MorphoShell reads as `true` or `false` (any other value is its error too).
const BOOLEANS: [&str; 2] = [
    "dialling_from_ansatz_rather_than_ref_state",
    "using_initial_glass_slide_z_coords_from_settings_file",
];

/// The entry MorphoShell reads as an integer.
const INTEGER: &str =
    "num_steps_to_use_gradient_descent_dynamics_for_before_switching_to_newtonian_dynamics";

/// One statement: its line (1-based), name and value.
#[derive(Clone, Debug)]
struct Statement {
    line: usize,
    name: String,
    value: String,
}

/// The statements of a settings file's text, in order (comments removed).
fn statements(text: &str, file: &str) -> Result<Vec<Statement>> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut start_line = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split("//").next().unwrap_or("");
        for ch in line.chars() {
            if ch.is_whitespace() {
                continue;
            }
            if cur.is_empty() {
                start_line = i + 1;
            }
            if ch == ';' {
                let Some((name, value)) = cur.split_once('=') else {
                    bail!("{file}:{start_line}: '{cur}' is not 'name = value;'");
                };
                out.push(Statement {
                    line: start_line,
                    name: name.to_string(),
                    value: value.to_string(),
                });
                cur.clear();
            } else {
                cur.push(ch);
            }
        }
    }
    if !cur.is_empty() {
        bail!("{file}:{start_line}: '{cur}' has no closing ';'");
    }
    Ok(out)
}

/// The values of a MorphoShell settings file, by name.
pub struct MorphoSettings {
    values: Vec<(String, Real)>,
}

impl MorphoSettings {
    /// The value of `name` (present: [`parse`] checked every entry).
    pub fn get(&self, name: &str) -> Real {
        self.values
            .iter()
            .find(|(n, _)| n == name)
            .map_or(0.0, |v| v.1)
    }
}

/// The value of entry `name` written as `value`, typed as MorphoShell reads it.
fn value(name: &str, value: &str, at: &str) -> Result<Real> {
    let v = if BOOLEANS.contains(&name) {
        match value {
            "true" => 1.0,
            "false" => 0.0,
            other => bail!("{at}: {name} = '{other}' is neither true nor false"),
        }
    } else if name == INTEGER {
        value
            .parse::<i64>()
            .map_err(|_| anyhow::anyhow!("{at}: {name} = '{value}' is not an integer"))?
            as Real
    } else {
        value
            .parse::<Real>()
            .map_err(|_| anyhow::anyhow!("{at}: {name} = '{value}' is not a number"))?
    };
    if !v.is_finite() {
        bail!("{at}: {name} = {value} is not finite");
    }
    Ok(v)
}

/// Parses a MorphoShell settings file's text (`file` names it in messages): MorphoShell's 23
/// entries ([`ENTRIES`]), or the 24 of the gravity layout ([`GRAVITY_ENTRIES`]) when the second
/// entry is that layout's.
pub fn parse(text: &str, file: &str) -> Result<MorphoSettings> {
    let st = statements(text, file)?;
    let layout: &[&str] = match st.get(1) {
        Some(s) if s.name == GRAVITY_ENTRIES[1] => &GRAVITY_ENTRIES,
        _ => &ENTRIES,
    };
    let required = layout.len();
    let mut values = Vec::new();
    for (k, s) in st.iter().enumerate() {
        let Some(&expected) = layout.get(k) else {
            bail!(
                "{file}:{}: unknown entry '{}' after the {required} that MorphoShell reads",
                s.line,
                s.name
            );
        };
        if s.name != expected {
            bail!(
                "{file}:{}: entry {} is '{}', but MorphoShell reads its settings by position and \
                 expects '{expected}' here",
                s.line,
                k + 1,
                s.name
            );
        }
        let v = value(expected, &s.value, &format!("{file}:{}", s.line))?;
        values.push((expected.to_string(), v));
    }
    if st.len() < required {
        let last = st.last().map_or(0, |s| s.line);
        bail!(
            "{file}: {} entries, but MorphoShell needs {required}: missing '{}' (after line {last})",
            st.len(),
            layout[st.len()]
        );
    }
    Ok(MorphoSettings { values })
}

/// The shellsim settings (TOML text) of MorphoShell settings `m`. `slide_speed` is the slide
/// speed in m/s when the slides move (computed from the mesh by the caller), `None` without a
/// mesh. `file` names the source in messages and the header.
pub fn to_toml(m: &MorphoSettings, file: &str, slide_speed: Option<Real>) -> Result<String> {
    let g = |n: &str| m.get(n);
    let nu = g("def_poisson_ratio");
    if !(nu > -1.0 && nu <= 0.5) {
        bail!("{file}: def_poisson_ratio = {nu} must lie in (-1, 0.5]");
    }
    if g("timestep_prefactor") <= 0.0 {
        bail!(
            "{file}: timestep_prefactor = {} must be positive",
            g("timestep_prefactor")
        );
    }
    let spacing = g("dial_factors_to_hold_at_spacing");
    let min_spacing = 1.0 / crate::settings::MAX_HOLDS as Real;
    if !(spacing >= min_spacing && spacing <= 1.0) {
        bail!(
            "{file}: dial_factors_to_hold_at_spacing = {spacing} must lie in [{min_spacing}, 1] \
             (at most {} holds)",
            crate::settings::MAX_HOLDS
        );
    }
    let mut t = String::new();
    let mut line = |s: String| {
        t.push_str(&s);
        t.push('\n');
    };
    line(format!(
        "# Converted by `shellsim import-morphoshell` from {file}: MorphoShell's physics and \
         prefactors."
    ));
    line("[material]".into());
    line("stretch_convention = \"morphoshell\"".into());
    line("bending = \"patch_fit\"".into());
    line(format!("poisson = {nu:?}"));
    let mu = g("ref_shear_modulus_if_uniform");
    if mu > 0.0 {
        line(format!(
            "young = {:?}   # 2 μ (1 + ν), μ = {mu:?}",
            2.0 * mu * (1.0 + nu)
        ));
        line("use_mesh_shear_modulus = false".into());
    } else {
        line("use_mesh_shear_modulus = true   # μ per face from ref_shear_moduli".into());
    }
    let h = g("ref_thickness_if_uniform");
    if h > 0.0 {
        line(format!("thickness = {h:?}"));
        line("use_mesh_thickness = false".into());
    } else {
        line("use_mesh_thickness = true   # from ref_thicknesses".into());
    }
    line(format!("density = {:?}", g("ref_density")));
    let gamma = g("bend_stiffening_scale_factor");
    if gamma > 0.0 {
        line(format!("bend_stiffening = {gamma:?}"));
    }
    line(String::new());
    line("[rest]".into());
    line("target = \"mesh\"   # abar_info / bbar_info of the mesh".into());
    line(String::new());
    line("[solver]".into());
    line("mode = \"explicit\"".into());
    line(String::new());
    line("[output]".into());
    line("morphoshell_fields = true   # angle deficits, strain measure, Cauchy stresses".into());
    line(String::new());
    line("[explicit]".into());
    line(format!(
        "time_step_prefactor = {:?}",
        g("timestep_prefactor")
    ));
    line(format!(
        "damping_prefactor_dial = {:?}",
        g("damping_prefactor_1")
    ));
    line(format!(
        "damping_prefactor_wait = {:?}",
        g("damping_prefactor_2")
    ));
    line(format!(
        "dial_long_times = {:?}   # each of the 1/spacing phases lasts dial_phase_time_prefactor",
        g("dial_phase_time_prefactor") / spacing
    ));
    line(format!(
        "frames_per_long_time = {:?}",
        g("outputs_per_char_long_time")
    ));
    line(format!(
        "window_long_times = {:?}",
        g("time_between_equil_checks_prefactor")
    ));
    line(format!(
        "gradient_descent_steps = {}",
        g("num_steps_to_use_gradient_descent_dynamics_for_before_switching_to_newtonian_dynamics")
            .max(0.0) as u64
    ));
    line(format!(
        "morphoshell_force_threshold = {:?}",
        g("force_to_char_force_ratio_equil_threshold")
    ));
    line(format!(
        "morphoshell_speed_threshold = {:?}",
        g("speed_to_char_speed_ratio_equil_threshold")
    ));
    line("# equilibrium = \"morphoshell\" would stop where MorphoShell stops (earlier).".into());
    let holds: Vec<String> = (1..)
        .map(|k| k as Real * spacing)
        .take_while(|&d| d < 1.0 - 1e-12)
        .map(|d| format!("{d:?}"))
        .collect();
    let from_ansatz = g("dialling_from_ansatz_rather_than_ref_state") != 0.0;
    if !holds.is_empty() || from_ansatz {
        line(String::new());
        line("[dial]".into());
    }
    if !holds.is_empty() {
        line(format!("holds = [{}]", holds.join(", ")));
    }
    if from_ansatz {
        line(
            "# Dial from the forms of the --restart file (a MorphoShell ansatz), from dial 0."
                .into(),
        );
        line("from = \"start\"".into());
    }
    let grav = g("grav_field_strength");
    if grav != 0.0 {
        line(String::new());
        line("[loads]".into());
        line(format!("gravity = [0.0, 0.0, {:?}]", -grav));
    }
    let k = g("slide_stiffness_prefactor");
    if k > 0.0 {
        line(String::new());
        line("[slides]".into());
        line("enabled = true".into());
        line(format!("stiffness_prefactor = {k:?}"));
        line(format!("friction = {:?}", g("slide_friction_coefficent")));
        line("contact_damping = 0.0   # MorphoShell's contact is undamped".into());
        if g("using_initial_glass_slide_z_coords_from_settings_file") != 0.0 {
            line(format!("upper = {:?}", g("initial_upper_slide_z_coord")));
            line(format!("lower = {:?}", g("initial_lower_slide_z_coord")));
        }
        let p = g("slide_speed_prefactor");
        if p != 0.0 {
            let Some(v) = slide_speed else {
                bail!(
                    "{file}: slide_speed_prefactor = {p} sets the slide's speed in units of the \
                     mesh's perimeter per bending long time: give the mesh too \
                     (shellsim import-morphoshell SETTINGS MESH)"
                );
            };
            line("control = \"speed\"".into());
            line(format!("speed = {v:?}   # {p} × L / T_bend"));
            line("travel = 1e30   # MorphoShell's slide never stops".into());
        }
    }
    Ok(t)
}
