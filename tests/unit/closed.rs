//! Closed surfaces: the icosphere generator, the exact enclosed volume and its gradient, and the
//! check that a mesh can hold a gas.

use shellsim::math::{Real, Vec3};
use shellsim::mesh::closed::{add_enclosed_volume_gradient, check_closed_outward, enclosed_volume};
use shellsim::mesh::generate::{icosphere, rectangle, Spacing};
use shellsim::mesh::Topology;
use std::f64::consts::PI;

/// The icosphere is a closed, consistently oriented manifold with outward normals and the
/// vertex and face counts `10·4ⁿ + 2`, `20·4ⁿ`; its volume approaches the sphere's at second
/// order in the edge length (the error quarters per subdivision), from below (it is inscribed).
#[test]
fn icosphere_volume_converges_to_the_sphere() {
    let r = 0.7;
    let exact = 4.0 / 3.0 * PI * r * r * r;
    let mut errs = Vec::new();
    for n in 0..5 {
        let m = icosphere(r, n);
        assert_eq!(m.positions.len(), 10 * 4usize.pow(n as u32) + 2);
        assert_eq!(m.faces.len(), 20 * 4usize.pow(n as u32));
        m.validate().unwrap();
        let topo = Topology::build(&m).unwrap();
        let v = check_closed_outward(&m, &topo).unwrap();
        assert!(m.positions.iter().all(|p| (p.norm() - r).abs() < 1e-12));
        assert!(v < exact, "an inscribed polyhedron holds less");
        errs.push((exact - v) / exact);
    }
    let ratios: Vec<Real> = errs.windows(2).map(|w| w[0] / w[1]).collect();
    println!("icosphere volume errors {errs:?}, ratios {ratios:?}");
    assert!(
        ratios[2..].iter().all(|&q| (q - 4.0).abs() < 0.2),
        "{ratios:?}"
    );
}

/// The volume does not depend on the origin (closed surface), and its gradient matches central
/// differences on a randomly perturbed icosphere to 1e-8 relative.
#[test]
fn enclosed_volume_gradient_matches_finite_differences() {
    let mut m = icosphere(1.0, 2);
    let mut rng = shellsim::mesh::generate::Rng::new(9);
    for p in &mut m.positions {
        *p += Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 0.05;
    }
    let v = enclosed_volume(&m.positions, &m.faces);
    let shifted: Vec<Vec3> = m
        .positions
        .iter()
        .map(|p| p + Vec3::new(3.0, -2.0, 5.0))
        .collect();
    let vs = enclosed_volume(&shifted, &m.faces);
    assert!((vs - v).abs() < 1e-12 * v, "{v} vs {vs}");
    let mut g = vec![Vec3::zeros(); m.positions.len()];
    add_enclosed_volume_gradient(&m.positions, &m.faces, &mut g);
    let h = 1e-6;
    let mut worst: Real = 0.0;
    let scale = g.iter().map(|v| v.norm()).fold(0.0, Real::max);
    for i in (0..m.positions.len()).step_by(7) {
        for k in 0..3 {
            let mut x = m.positions.clone();
            x[i][k] += h;
            let vp = enclosed_volume(&x, &m.faces);
            x[i][k] -= 2.0 * h;
            let vm = enclosed_volume(&x, &m.faces);
            let fd = (vp - vm) / (2.0 * h);
            worst = worst.max((fd - g[i][k]).abs() / scale);
        }
    }
    assert!(worst < 1e-8, "{worst:e}");
}

/// An open sheet is refused naming an open edge; an inward (reversed) sphere is refused with
/// the fix named.
#[test]
fn open_and_inward_meshes_are_refused() {
    let sheet = rectangle(0.0, 0.0, 1.0, 1.0, 0.25, Spacing::default());
    let topo = Topology::build(&sheet).unwrap();
    let e = check_closed_outward(&sheet, &topo).unwrap_err().to_string();
    assert!(e.contains("closed surface") && e.contains("edge"), "{e}");
    let mut inward = icosphere(1.0, 1);
    for f in &mut inward.faces {
        f.swap(1, 2);
    }
    let topo = Topology::build(&inward).unwrap();
    let e = check_closed_outward(&inward, &topo)
        .unwrap_err()
        .to_string();
    assert!(e.contains("inward") && e.contains("reverse"), "{e}");
}
