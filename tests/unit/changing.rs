//! A term whose elements change during a run (the `ChangingElements` capability): a test term of short-range
//! repulsion between the vertices of two sheets, `E = Σ k (r − d)³/3` over the pairs closer
//! than `r`. A square falling onto a fixed one gathers pairs as it arrives: the drivers rebuild
//! the pattern when the pairs change, the finite-difference check holds on the current pairs,
//! the square comes to rest carried by the repulsion, and the run is bitwise identical on 1
//! and 2 threads.

use shellsim::assembly::{assemble_elements, ElementMap, Pattern, Want};
use shellsim::body::Body;
use shellsim::energy::term::{ChangingElements, Reports, Stencil, Term};
use shellsim::energy::HessianProjection;
use shellsim::energy::Potential;
use shellsim::math::{Mat3, Real, SMat, SVec, Vec3};
use shellsim::mesh::generate::{rectangle, Spacing};
use shellsim::mesh::Mesh;
use shellsim::model::Scene;
use shellsim::settings::Settings;

/// Repulsion between vertices of different sheets (`sheet[v]`) closer than `r` (m), stiffness
/// `k` (N/m²). DOF order per element: `x_i`, then `x_j`.
struct Repulsion {
    r: Real,
    k: Real,
    sheet: Vec<u8>,
}

impl Repulsion {
    /// The pairs `(i, j)`, `i < j`, of different sheets closer than `r` at `x`, sorted.
    fn pairs(&self, x: &[Vec3]) -> Stencil {
        let (mut nodes, mut anchors) = (Vec::new(), Vec::new());
        for i in 0..x.len() {
            for j in i + 1..x.len() {
                if self.sheet[i] != self.sheet[j] && (x[i] - x[j]).norm() < self.r {
                    nodes.extend_from_slice(&[i, j]);
                    anchors.push((x[i] + x[j]) / 2.0);
                }
            }
        }
        Stencil {
            slot_dofs: vec![3, 3],
            nodes,
            anchors,
        }
    }

    fn element(
        &self,
        nodes: &[usize],
        x: &[Vec3],
        grad: Option<&mut SVec<6>>,
        hess: Option<&mut SMat<6, 6>>,
    ) -> Real {
        let d = x[nodes[0]] - x[nodes[1]];
        let l = d.norm();
        let (mut g, mut h) = (SVec::<6>::zeros(), SMat::<6, 6>::zeros());
        let e = if l < self.r && l > 0.0 {
            let u = d / l;
            let s = self.r - l;
            let (d1, d2) = (-self.k * s * s, 2.0 * self.k * s);
            let gi = u * d1;
            let hi = u * u.transpose() * d2 + (Mat3::identity() - u * u.transpose()) * (d1 / l);
            g.fixed_rows_mut::<3>(0).copy_from(&gi);
            g.fixed_rows_mut::<3>(3).copy_from(&(-gi));
            h.fixed_view_mut::<3, 3>(0, 0).copy_from(&hi);
            h.fixed_view_mut::<3, 3>(3, 3).copy_from(&hi);
            h.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-hi));
            h.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-hi));
            self.k * s * s * s / 3.0
        } else {
            0.0
        };
        if let Some(out) = grad {
            out.copy_from(&g);
        }
        if let Some(out) = hess {
            out.copy_from(&h);
        }
        e
    }
}

impl ChangingElements for Repulsion {
    fn stencil_at(&self, _: &Body, x: &[Vec3], _: &[Real], _: Real) -> Stencil {
        self.pairs(x)
    }
}

impl Term for Repulsion {
    fn name(&self) -> &'static str {
        "repulsion"
    }
    fn stencil(&self, body: &Body) -> Stencil {
        self.pairs(&body.mesh.positions)
    }
    fn changing(&self) -> Option<&dyn ChangingElements> {
        Some(self)
    }
    fn eval(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        _phi: &[Real],
        want: Want,
        projection: HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        assemble_elements::<6, 2, _>(
            map,
            |_, nodes, g, h| self.element(nodes, x, g, h),
            pot.node_fixed,
            projection,
            want,
            grad,
            values,
            &pot.pattern.col_ptr,
        )
    }

    fn reports(&self) -> Option<&dyn Reports> {
        Some(self)
    }
}

impl Reports for Repulsion {
    /// The repulsion's vertical force on the upper sheet (N).
    fn observables(&self, _: &Potential, x: &[Vec3], _: &[Real]) -> Vec<(String, Real)> {
        let st = self.pairs(x);
        let mut f = 0.0;
        for p in st.nodes.chunks(2) {
            let mut g = SVec::<6>::zeros();
            self.element(p, x, Some(&mut g), None);
            // The upper sheet is sheet 1; the force is minus the gradient.
            f -= if self.sheet[p[0]] == 1 { g[2] } else { g[5] };
        }
        vec![("repulsion_force_z".into(), f)]
    }
}

/// Two 10 cm squares (edge 5 cm): sheet 0 at z = 0, sheet 1 at z = `gap`.
fn two_squares(gap: Real) -> (Mesh, Vec<u8>) {
    let a = rectangle(0.0, 0.0, 0.1, 0.1, 0.05, Spacing::default());
    let mut m = a.clone();
    let n = a.positions.len();
    m.positions
        .extend(a.positions.iter().map(|p| p + Vec3::new(0.0, 0.0, gap)));
    m.faces
        .extend(a.faces.iter().map(|f| [f[0] + n, f[1] + n, f[2] + n]));
    let sheet = (0..2 * n).map(|v| u8::from(v >= n)).collect();
    (m, sheet)
}

fn scene(settings: &str, gap: Real) -> Scene {
    let (mesh, sheet) = two_squares(gap);
    let mut sc = Scene::build(
        mesh,
        Settings::from_str_with(settings, "test", &[]).unwrap(),
    )
    .unwrap();
    let term = Repulsion {
        r: 0.02,
        k: 1e5,
        sheet,
    };
    assert!(
        sc.terms.push(Box::new(term)).is_ok(),
        "the terms are shared"
    );
    sc
}

const FALLING: &str = "[material]\nyoung = 1e6\nthickness = 0.001\ndensity = 1000\n\
    [solver]\nmode = \"dynamic\"\nsymmetry_breaking = 0\n\
    [time]\nend = 0.6\ndt = 1e-3\ndt_max = 0.01\noutput_interval = 0.2\ndamping = 0.01\n\
    [loads]\ngravity = [0, 0, -9.81]\n\
    [constraints]\nfix_boxes = [{ min = [-1, -1, -0.001], max = [1, 1, 0.001] }]\n";

/// The pattern follows the pairs: none at the start (5 cm apart), some once the upper square
/// has fallen within 2 cm; the finite-difference check holds on the pairs of a state.
#[test]
fn the_pattern_follows_changing_elements() {
    let sc = scene(FALLING, 0.05);
    let p = Pattern::for_scene(&sc);
    let i = sc.terms.len() - 1;
    assert_eq!(p.maps[i].len(), 0);
    let x: Vec<Vec3> = sc
        .body
        .mesh
        .positions
        .iter()
        .enumerate()
        .map(|(v, q)| {
            if v >= 9 {
                q - Vec3::new(0.002 * (v % 3) as Real, 0.0, 0.037)
            } else {
                *q
            }
        })
        .collect();
    let phi = vec![0.0; sc.num_scalar_dofs()];
    let q = p.refreshed(&sc, &x, &phi, 0.0).expect("the pairs changed");
    assert!(q.maps[i].len() >= 9, "{} pairs", q.maps[i].len());
    assert!(!q.same_union(&p));
    assert!(
        q.refreshed(&sc, &x, &phi, 0.0).is_none(),
        "same state, same pairs"
    );
    let pot = Potential::new(&sc, &q);
    super::terms::fd_check(
        &sc,
        &q,
        &x,
        &phi,
        "repulsion",
        1,
        |g, h| g.max(h),
        |x, phi, want, g, h| {
            g.iter_mut().for_each(|v| *v = 0.0);
            h.iter_mut().for_each(|v| *v = 0.0);
            sc.terms[i].eval(
                &pot,
                &q.maps[i],
                x,
                phi,
                want,
                HessianProjection::None,
                g,
                h,
            )
        },
    );
}

/// The upper square falls 3 cm onto the repulsion of the fixed one and comes to rest on it:
/// the drivers rebuilt the pattern as pairs appeared (6 times), the repulsion carries the
/// square's weight (to 1e-4, for the damping's last motion; measured 3e-7), and the frames of 1
/// and 2 threads are identical.
#[test]
fn a_falling_square_rests_on_changing_pairs_on_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let mut last = Vec::new();
    for threads in [1, 2] {
        let sc = scene(FALLING, 0.05);
        let out = dir.path().join(format!("t{threads}"));
        let mut writer = shellsim::output::Writer::new(&out, &sc, false).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let summary = pool
            .install(|| {
                shellsim::integrate::run(
                    &sc,
                    &mut writer,
                    &mut shellsim::integrate::Quiet,
                    threads,
                    None,
                )
            })
            .unwrap();
        assert!(summary.converged, "{}", summary.reason);
        assert!(summary.element_changes >= 1 && summary.pattern_rebuilds >= 1);
        let text = std::fs::read_to_string(out.join("log.csv")).unwrap();
        let head: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let row: Vec<&str> = text.lines().last().unwrap().split(',').collect();
        let col = |k: &str| -> Real {
            row[head.iter().position(|h| *h == k).unwrap()]
                .parse()
                .unwrap()
        };
        let weight = 1000.0 * 0.001 * 0.01 * 9.81;
        let f = col("repulsion_force_z");
        println!(
            "{threads} thread(s): force {f} N vs weight {weight} N, {} element changes, {} \
             pattern rebuilds",
            summary.element_changes, summary.pattern_rebuilds
        );
        assert!((f / weight - 1.0).abs() < 1e-4, "{f} vs {weight}");
        let frame = shellsim::mesh::io::read_mesh(&out.join("frame_00003.vtu")).unwrap();
        assert!(frame.positions[9..].iter().all(|p| p.z > 0.0 && p.z < 0.02));
        last.push(frame.positions);
    }
    assert_eq!(last[0], last[1], "1 and 2 threads differ");
}
