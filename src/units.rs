//! Units of the frames' fields and `log.csv`'s columns: the one table that `shellsim render`'s
//! colour bar and `shellsim plot`'s axes label with, and that docs/files.md shows (a test
//! checks the two agree).

/// Name (a trailing `*` matches any suffix), unit (`–`: dimensionless), and where it is
/// found. The first match wins.
pub const UNITS: &[(&str, &str, &str)] = &[
    ("displacement", "m", "vertex field"),
    ("velocity", "m/s", "vertex field"),
    ("constraint_indicators", "–", "vertex field"),
    ("reaction", "N", "vertex field"),
    ("node_tags", "–", "vertex field"),
    ("a", "–", "face field"),
    ("abar", "–", "face field"),
    ("b", "1/m", "face field"),
    ("bbar", "1/m", "face field"),
    ("mean_curvature", "1/m", "face field"),
    ("gauss_curvature", "1/m²", "face field"),
    ("k1", "1/m", "face field"),
    ("k2", "1/m", "face field"),
    ("max_stretch", "–", "face field"),
    ("stretching_energy_density", "J/m²", "face field"),
    ("bending_energy_density", "J/m²", "face field"),
    ("thickness", "m", "face field"),
    ("pressure", "Pa", "face field"),
    ("contact_pressure", "Pa", "face field"),
    ("contact_gap", "m", "face field"),
    ("tri_tags", "–", "face field"),
    ("patch_condition", "–", "face field"),
    ("edge_angles", "rad", "face field"),
    ("moment_turn", "rad", "face field"),
    ("moisture_top", "–", "face field"),
    ("moisture_bottom", "–", "face field"),
    ("temperature_top", "K", "face field"),
    ("temperature_bottom", "K", "face field"),
    ("temperature_max_top", "K", "face field"),
    ("temperature_max_bottom", "K", "face field"),
    ("angle_deficit", "rad", "vertex field"),
    ("angle_deficit_gauss_curvature", "1/m²", "vertex field"),
    ("strain_measure", "–", "face field"),
    ("cauchy_stress_eigval_*", "N/m", "face field"),
    ("dimless_*", "–", "face field"),
    ("cauchy_stress_eigvec_*", "–", "face field"),
    ("frame", "–", "log.csv"),
    ("mass", "kg", "log.csv"),
    ("time", "s", "log.csv"),
    ("dial", "–", "log.csv"),
    ("energy_*", "J", "log.csv"),
    ("point_load_displacement", "m", "log.csv"),
    ("traction_displacement", "m", "log.csv"),
    ("moment_rotation", "rad", "log.csv"),
    ("self_contact_pairs", "–", "log.csv"),
    ("self_contact_gap", "–", "log.csv"),
    ("self_contact_force", "N", "log.csv"),
    ("self_contact_friction", "N", "log.csv"),
    ("self_contact_broad_seconds", "s", "log.csv"),
    ("self_contact_ccd_seconds", "s", "log.csv"),
    ("self_contact_assembly_seconds", "s", "log.csv"),
    ("mesh_obstacles_pairs", "–", "log.csv"),
    ("mesh_obstacles_gap", "–", "log.csv"),
    ("mesh_obstacles_force", "N", "log.csv"),
    ("mesh_obstacles_friction", "N", "log.csv"),
    ("mesh_obstacles_broad_seconds", "s", "log.csv"),
    ("mesh_obstacles_ccd_seconds", "s", "log.csv"),
    ("mesh_obstacles_assembly_seconds", "s", "log.csv"),
    ("gas_pressure", "Pa", "log.csv"),
    ("gas_volume", "m³", "log.csv"),
    ("skin_volume_ratio", "–", "log.csv"),
    ("slide_upper_z", "m", "log.csv"),
    ("slide_lower_z", "m", "log.csv"),
    ("slide_gap", "m", "log.csv"),
    ("slide_upper_force", "N", "log.csv"),
    ("slide_lower_force", "N", "log.csv"),
    ("arc_length", "–", "log.csv"),
    ("negative_eigenvalues", "–", "log.csv"),
    ("critical_point", "–", "log.csv"),
    ("reaction_force_*", "N", "log.csv"),
    ("reaction_moment_*", "N·m", "log.csv"),
    ("residual", "–", "log.csv"),
    ("newton_iterations", "–", "log.csv"),
    ("steps", "–", "log.csv"),
    ("shifted_iterations", "–", "log.csv"),
    ("gauss_newton_iterations", "–", "log.csv"),
    ("rejected_steps", "–", "log.csv"),
    ("wall_seconds", "s", "log.csv"),
];

/// The unit of a field or log column: `Some("")` for a dimensionless one, `None` for a name
/// the table does not know.
pub fn unit(name: &str) -> Option<&'static str> {
    UNITS.iter().find_map(|(n, u, _)| {
        let hit = match n.strip_suffix('*') {
            Some(prefix) => name.starts_with(prefix),
            None => name == *n,
        };
        hit.then_some(if *u == "–" { "" } else { *u })
    })
}

/// `name (unit)`, or `name` alone when it is dimensionless or unknown.
pub fn label(name: &str) -> String {
    match unit(name) {
        Some(u) if !u.is_empty() => format!("{name} ({u})"),
        _ => name.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_by_name_and_prefix() {
        assert_eq!(unit("mean_curvature"), Some("1/m"));
        assert_eq!(unit("energy_bending"), Some("J"));
        assert_eq!(unit("dimless_cauchy_stress_eigval_1"), Some(""));
        assert_eq!(unit("cauchy_stress_eigval_2"), Some("N/m"));
        assert_eq!(unit("max_stretch"), Some(""));
        assert_eq!(unit("no_such_thing"), None);
        assert_eq!(label("time"), "time (s)");
        assert_eq!(label("max_stretch"), "max_stretch");
    }

    /// docs/files.md shows this table, row for row.
    #[test]
    fn docs_show_the_table() {
        let doc =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/files.md")).unwrap();
        let rows: Vec<(String, String, String)> = doc
            .lines()
            .filter_map(|l| {
                let c: Vec<&str> = l
                    .trim()
                    .trim_matches('|')
                    .split('|')
                    .map(str::trim)
                    .collect();
                (c.len() == 3 && c[0].starts_with('`') && c[2].ends_with("field")
                    || c.len() == 3 && c[2] == "log.csv")
                    .then(|| (c[0].trim_matches('`').to_string(), c[1].into(), c[2].into()))
            })
            .collect();
        let want: Vec<(String, String, String)> = UNITS
            .iter()
            .map(|(n, u, w)| (n.to_string(), u.to_string(), w.to_string()))
            .collect();
        assert_eq!(rows, want);
    }
}
