//! The body: the validated mesh, its topology, rest forms, per-face material, per-vertex mass
//! and the supports, built once from the settings and the mesh file. It knows no energy terms
//! and keeps no settings: the model ([`crate::model::Scene`]) adds the terms the settings
//! enable.

pub mod hold;
mod lame;
pub mod patch;
pub mod select;

pub use lame::Lame2d;

use crate::math::{Mat3, Real, Sym2, Vec3};
use crate::mesh::{Mesh, MeshError, Topology};
use crate::rest::laws::GrowthInputs;
use crate::rest::RestForms;
use crate::settings::Settings;

/// The sheet: everything about it that the energy terms and the drivers read, derived once.
#[derive(Clone, Debug)]
pub struct Body {
    /// The input mesh (reference positions and fields).
    pub mesh: Mesh,
    /// Its connectivity.
    pub topo: Topology,
    /// Rest forms at dial 0 and 1.
    pub rest: RestForms,
    /// Thickness per face (m).
    pub thickness: Vec<Real>,
    /// Young's modulus per face (Pa).
    pub young: Vec<Real>,
    /// Plane-stress Lamé parameters per face.
    pub lame: Vec<Lame2d>,
    /// Multiplier on stretching (1 Koiter, 4 MorphoShell).
    pub stretch_factor: Real,
    /// Whether the sheet has a bending energy (`material.bending` is not `"none"`).
    pub has_bending: bool,
    /// The bending stiffening factor γ (`material.bend_stiffening`), if any.
    pub bend_stiffening: Option<Real>,
    /// Lumped mass per vertex: Σ ρ h A / 3 over incident faces, reference areas (kg).
    pub mass: Vec<Real>,
    /// True for fixed vertices.
    pub fixed: Vec<bool>,
    /// Force scale F = max(E h) × mean edge length (N), for the convergence test.
    pub force_scale: Real,
    /// Mean edge length of the input mesh (m).
    pub mean_edge: Real,
    /// Warnings found while building (unused vertices, ill-conditioned patches, ...).
    pub warnings: Vec<String>,
    /// Each face's corner shift from the input's order
    /// ([`Mesh::anchor_faces_at_wide_angles`]): frames are written in the input's order.
    pub corner_shift: Vec<u8>,
    /// The bending model (`material.bending`).
    pub bending: crate::settings::BendingModel,
    /// Mass density ρ (kg/m³, `material.density`).
    pub density: Real,
    /// Poisson's ratio ν (`material.poisson`).
    pub poisson: Real,
    /// Patch-fit bending data per face (`material.bending = "patch_fit"`), else empty.
    pub patches: Vec<patch::Patch>,
    /// Edge-DOF models: each face's orientation sign `σ` on its edges (+1 for the edge's first
    /// face, −1 for its second), else empty.
    pub edge_sign: Vec<[Real; 3]>,
    /// The boundary edges whose rotation a clamp holds or a symmetry plane sets: with edge
    /// DOFs, those DOFs are held ([`crate::model::Scene::node_fixed`]).
    pub clamped_edges: Vec<usize>,
    /// Per edge, its mid-edge normal when a clamp or a symmetry plane sets it in space (the
    /// edge-DOF bending models, [`crate::geometry::EdgeNormal`]); empty when none is.
    pub edge_normal: Vec<Option<crate::geometry::EdgeNormal>>,
    /// Position DOFs (`3v + k`) held at their current values while their vertex is otherwise
    /// free: the components held by `[[constraints.support]]`, by symmetry planes along an
    /// axis and by partial paths, and the automatic rigid pins along an axis
    /// ([`hold::rigid_pins`]); sorted. Vertices with a held direction off the axes are in
    /// [`Body::skew`] instead.
    pub pinned_dofs: Vec<usize>,
    /// The position DOFs of [`Body::pinned_dofs`] that supports and partial paths hold (not
    /// the automatic rigid pins), sorted.
    pub held_dofs: Vec<usize>,
    /// Vertices held along directions off the coordinate axes (oblique symmetry planes, the
    /// automatic rigid pins), with the projector onto the directions they may move in
    /// ([`hold::Skew`]), ascending.
    pub skew: Vec<hold::Skew>,
    /// The rigid motions that the supports (before the automatic pins) leave free: only the
    /// translations among them under dead loads (gravity, point, traction, pressure, moment
    /// loads), whose rotations the pins leave alone.
    pub rigid: hold::RigidModes,
    /// Per-face inputs of the growth law.
    pub growth: GrowthInputs,
    /// Per face, the rest thickness at dial 1 over the reference thickness, when a growth law
    /// scales it (uniform volumetric growth); empty otherwise (see
    /// [`crate::energy::Potential::thickness`]).
    pub grown_thickness: Vec<Real>,
    /// The ground plane (`contact.enabled`), else `None`.
    pub ground: Option<crate::contact::Ground>,
    /// Vertices on prescribed paths, their displacement at dial 1 (m) and the components that
    /// follow it: a vertex whose three components follow is held, otherwise its path's
    /// components are in [`Body::pinned_dofs`].
    pub prescribed: Vec<(usize, Vec3, [bool; 3])>,
    /// Every support of `[constraints]` (and the automatic rigid pins) with the position DOFs
    /// it holds, for its reaction.
    pub supports: Vec<SupportGroup>,
}

/// The per-face field `name`, checked to lie in (0, `max`] (an error naming the face), when
/// `used` (the settings `key` says so); `None` when not used or absent. An unused field is not read, so MorphoShell's
/// placeholder −1234 (written when its settings' uniform value is used) does no harm there.
fn positive_face_field(
    mesh: &Mesh,
    name: &str,
    max: Real,
    (key, used): (&str, bool),
) -> Result<Option<Vec<Real>>, MeshError> {
    if !used {
        return Ok(None);
    }
    let Some(f) = mesh.face_field(name, 1)? else {
        return Ok(None);
    };
    if let Some(i) = f.data.iter().position(|&v| !(v > 0.0 && v <= max)) {
        let placeholder = if f.data[i] == -1234.0 {
            format!(
                " (MorphoShell's placeholder for the settings' uniform value; to use one, set \
                 material.{key} = false)"
            )
        } else {
            String::new()
        };
        return Err(mesh.invalid(format!(
            "face field '{name}' must lie in (0, {}], but face {i} has {}{placeholder}",
            crate::math::human(max),
            crate::math::human(f.data[i])
        )));
    }
    Ok(Some(f.data.clone()))
}

impl Body {
    /// The skew vertices ([`Body::skew`]), ascending.
    pub fn skew_vertices(&self) -> Vec<usize> {
        self.skew.iter().map(|s| s.vertex).collect()
    }

    /// The projector of skew vertex `v` ([`hold::Skew::free`]), `None` for any other node.
    pub fn skew_projector(&self, v: usize) -> Option<Mat3> {
        self.skew
            .binary_search_by_key(&v, |s| s.vertex)
            .ok()
            .map(|i| self.skew[i].free)
    }

    /// Applies the skew vertices' projectors to a DOF vector (gradient, step, direction): the
    /// components along the directions they hold become zero.
    pub fn project_skew(&self, g: &mut [Real]) {
        for s in &self.skew {
            let d = 3 * s.vertex;
            let p = s.free * Vec3::new(g[d], g[d + 1], g[d + 2]);
            g[d..d + 3].copy_from_slice(p.as_slice());
        }
    }

    /// Validates the mesh and builds the body, in stages: the mesh and its topology, the
    /// material per face, the rest forms (reference, targets, growth), the masses, the supports,
    /// the checks that the problem is posed, and the ground. Errors name the file, field and
    /// index.
    pub fn build(mut mesh: Mesh, settings: &Settings) -> Result<Body, MeshError> {
        let unused = mesh.validate()?;
        let corner_shift = mesh.anchor_faces_at_wide_angles();
        let topo = Topology::build(&mesh)?;
        check_not_folded(&mesh, &topo)?;
        let mut warnings = Vec::new();
        if !unused.is_empty() {
            warnings.push(format!(
                "{}: {} vertices are used by no face (first: {}); they are held fixed",
                mesh.name(),
                unused.len(),
                unused[0]
            ));
        }
        warnings.extend(mesh.unknown_field_warnings());
        let nv = mesh.positions.len();
        let m = &settings.material;
        let FaceMaterial {
            thickness,
            young,
            lame,
        } = face_material(&mesh, m)?;
        let is_unused = unused_mask(nv, &unused);
        // The supports first: the boundary normals they set enter the reference curvature.
        let Supports {
            fixed,
            clamped_edges,
            edge_normal,
            prescribed,
            mut comp,
            mut dirs,
            mut groups,
        } = supports(&mesh, &topo, settings, &is_unused)?;
        let RestStage {
            rest,
            edge_sign,
            growth,
            grown_thickness,
        } = rest_forms(&mesh, &topo, settings, &thickness, &edge_normal)?;
        if settings.moisture.enabled {
            check_moisture_regions(&mesh, settings)?;
        }
        if settings.temperature.enabled {
            check_heat_regions(&mesh, settings)?;
        }
        let mass = lumped_masses(&mesh, &thickness, m.density);
        // Free: no vertex that carries the sheet is held (unused vertices are held, inertly).
        let free = unused.len() < nv
            && (0..nv).all(|v| is_unused[v] || !fixed[v])
            && comp.iter().all(|c| *c == [false; 3])
            && dirs.iter().all(|d| d.is_empty());
        check_posed(&mesh, settings, free)?;
        let ground = settings
            .contact
            .enabled
            .then(|| build_ground(&mesh, &settings.contact, &thickness, &young))
            .transpose()?;
        let patches = if m.bending == crate::settings::BendingModel::PatchFit {
            let (p, w) = patch::build_patches(&mesh)?;
            warnings.extend(w);
            p
        } else {
            Vec::new()
        };
        // The rigid motions the supports leave free. In statics without obstacles or a ground
        // (which hold the sheet where they touch it, so pins would carry their reaction) they are
        // removed by statically determinate pins. Dead loads are not invariant under
        // rotations: pinning a rotation would make the pins carry a reaction. With loads only
        // the free translations are pinned then (balanced loads are invariant under them);
        // rotations the loads leave free get the solver's tiny shift.
        let used: Vec<bool> = is_unused.iter().map(|&u| !u).collect();
        let dead_loads =
            settings.loads.any_external() || settings.loads.gravity.iter().any(|&g| g != 0.0);
        let rigid = hold::free_modes(&mesh, &used, &fixed, &comp, &dirs, dead_loads);
        let pinnable = settings.obstacles.is_empty()
            && !settings.contact.enabled
            && settings.solver.mode == crate::settings::Mode::Static;
        let mut pin_dofs = Vec::new();
        if pinnable && !rigid.modes.is_empty() {
            let free_vertex: Vec<bool> = (0..nv).map(|v| used[v] && !fixed[v]).collect();
            let pins = hold::rigid_pins(&mesh, &free_vertex, &rigid);
            if !pins.is_empty() {
                let gi = groups.len();
                let mut group = SupportGroup {
                    name: "rigid_pins".into(),
                    dofs: Vec::new(),
                    directions: Vec::new(),
                };
                for &(v, d) in &pins {
                    match (0..3).find(|&k| d[k].abs() == 1.0) {
                        Some(k) if !comp[v][k] => {
                            comp[v][k] = true;
                            group.dofs.push(3 * v + k);
                            pin_dofs.push(3 * v + k);
                        }
                        _ => dirs[v].push((d, gi)),
                    }
                }
                group.dofs.sort_unstable();
                groups.push(group);
            }
        }
        let hold::Final { pinned_dofs, skew } = hold::finalise(&fixed, &comp, &dirs, &mut groups);
        let held_dofs: Vec<usize> = pinned_dofs
            .iter()
            .copied()
            .filter(|d| !pin_dofs.contains(d))
            .collect();
        let mean_edge = mesh.mean_edge_length();
        let eh = young
            .iter()
            .zip(&thickness)
            .map(|(e, h)| e * h)
            .fold(0.0, Real::max);
        Ok(Body {
            stretch_factor: m.stretch_convention.factor(),
            has_bending: m.bending != crate::settings::BendingModel::None,
            bend_stiffening: m.bend_stiffening,
            bending: m.bending,
            density: m.density,
            poisson: m.poisson,
            force_scale: eh * mean_edge,
            mean_edge,
            mesh,
            topo,
            rest,
            thickness,
            young,
            lame,
            mass,
            fixed,
            warnings,
            corner_shift,
            patches,
            edge_sign,
            clamped_edges,
            edge_normal,
            pinned_dofs,
            held_dofs,
            skew,
            rigid,
            growth,
            grown_thickness,
            ground,
            prescribed,
            supports: groups,
        })
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.mesh.positions.len()
    }

    /// Number of faces.
    pub fn num_faces(&self) -> usize {
        self.mesh.faces.len()
    }

    /// Face `f`'s vertices in the input mesh's order (the scene may start a sliver at another
    /// corner, [`Body::corner_shift`]).
    pub fn input_face(&self, f: usize) -> [usize; 3] {
        let k = self.corner_shift.get(f).copied().unwrap_or(0) as usize;
        let face = self.mesh.faces[f];
        [0, 1, 2].map(|i| face[(i + 3 - k) % 3])
    }

    /// Every face in the input mesh's order.
    pub fn input_faces(&self) -> Vec<[usize; 3]> {
        (0..self.num_faces()).map(|f| self.input_face(f)).collect()
    }

    /// Reorders per-face slot values (3 per face) between the scene's corner order and the
    /// input's: `to_input` maps the scene's to the input's, otherwise back.
    pub fn reorder_slots(&self, data: &mut [Real], to_input: bool) {
        for (f, v) in data.chunks_exact_mut(3).enumerate() {
            let k = self.corner_shift.get(f).copied().unwrap_or(0) as usize;
            if k == 0 {
                continue;
            }
            let old = [v[0], v[1], v[2]];
            for j in 0..3 {
                // The scene's slot j is the input's slot (k + j) mod 3.
                if to_input {
                    v[(k + j) % 3] = old[j];
                } else {
                    v[j] = old[(k + j) % 3];
                }
            }
        }
    }

    /// The 3 extra vertices of each face's bending stencil: the neighbours' far vertices
    /// (mid-edge) or the patch nodes (patch fit).
    pub fn stencil_extra(&self) -> Vec<[usize; 3]> {
        if self.patches.is_empty() {
            self.topo.opposite_vertex.clone()
        } else {
            self.patches.iter().map(|p| p.nodes).collect()
        }
    }

    /// Whether the bending model has one DOF per edge.
    pub fn has_edge_dofs(&self) -> bool {
        !self.edge_sign.is_empty()
    }

    /// Number of edge DOFs (0 without them).
    pub fn num_edge_dofs(&self) -> usize {
        if self.has_edge_dofs() {
            self.topo.edges.len()
        } else {
            0
        }
    }

    /// Makes the forms of the state `(x, phi)` the dial's starting forms (`dial.from =
    /// "start"`, MorphoShell's dialling from an ansatz): ā and b̄ then go linearly from the
    /// start's a and b to their targets. The director law's stretch dial is replaced by that
    /// linear dial to its target metric.
    pub fn dial_from_state(&mut self, x: &[Vec3], phi: &[Real]) {
        let (a, b) = self.forms(x, phi);
        let rest = &mut self.rest;
        rest.abar0 = a;
        rest.bbar0 = b;
        rest.lce.clear();
    }

    /// First and second fundamental forms of every face at `x` (edge DOFs `phi`, empty without
    /// them), with this scene's bending model.
    pub fn forms(&self, x: &[Vec3], phi: &[Real]) -> (Vec<Sym2>, Vec<Sym2>) {
        let body = self;
        if let Some(variant) = self.bending.angle_variant() {
            return midedge_angle_forms(body, variant, x, phi);
        }
        if body.patches.is_empty() {
            return crate::rest::mesh_forms(x, &body.mesh, &body.topo);
        }
        body.mesh
            .faces
            .iter()
            .zip(&body.patches)
            .map(|(f, p)| {
                let xs = [
                    x[f[0]],
                    x[f[1]],
                    x[f[2]],
                    x[p.nodes[0]],
                    x[p.nodes[1]],
                    x[p.nodes[2]],
                ];
                (
                    crate::geometry::first_fundamental_form(&[xs[0], xs[1], xs[2]]),
                    patch::patch_b(&xs, &p.weights),
                )
            })
            .unzip()
    }

    /// Moves the vertices on prescribed paths to `reference + dial × displacement`.
    pub fn prescribe(&self, x: &mut [Vec3], dial: Real) {
        for &(v, u, mask) in &self.prescribed {
            for k in 0..3 {
                if mask[k] {
                    x[v][k] = self.mesh.positions[v][k] + u[k] * dial;
                }
            }
        }
    }

    /// Reference (input) positions.
    pub fn reference_positions(&self) -> &[Vec3] {
        &self.mesh.positions
    }
}

/// Rejects a reference mesh folded flat onto itself across an edge: it has no mid-edge normal
/// there.
fn check_not_folded(mesh: &Mesh, topo: &Topology) -> Result<(), MeshError> {
    let normal = |f: usize| {
        let [a, b, c] = mesh.face_positions(f);
        (b - a).cross(&(c - a)).normalize()
    };
    for (e, ef) in topo.edge_faces.iter().enumerate() {
        if ef[1] != crate::mesh::topology::NONE && normal(ef[0]).dot(&normal(ef[1])) < -1.0 + 1e-9 {
            return Err(mesh.invalid(format!(
                "faces {} and {} are folded onto each other across edge {:?} (their normals \
                 are opposite): the reference surface must not fold back on itself",
                ef[0], ef[1], topo.edges[e]
            )));
        }
    }
    Ok(())
}

/// The material of every face.
struct FaceMaterial {
    /// Thickness (m).
    thickness: Vec<Real>,
    /// Young's modulus (Pa).
    young: Vec<Real>,
    /// Plane-stress Lamé parameters.
    lame: Vec<Lame2d>,
}

/// Per face: the thickness, Young's modulus and the plane-stress Lamé parameters, from the
/// mesh's fields when the settings use them, else the settings' uniform values.
fn face_material(mesh: &Mesh, m: &crate::settings::Material) -> Result<FaceMaterial, MeshError> {
    let nf = mesh.faces.len();
    // Uniform values, then regions, then the mesh's fields.
    let (mut thickness, mut young) = (vec![m.thickness; nf], vec![m.young; nf]);
    for (i, r) in m.regions.iter().enumerate() {
        let what = format!("material.regions[{i}]");
        for f in select::faces_matching(mesh, &r.tags, r.inside.as_ref(), &what)? {
            if let Some(h) = r.thickness {
                thickness[f] = h;
            }
            if let Some(e) = r.young {
                young[f] = e;
            }
        }
    }
    if let Some(t) = positive_face_field(
        mesh,
        "ref_thicknesses",
        crate::mesh::MAX_COORDINATE,
        ("use_mesh_thickness", m.use_mesh_thickness),
    )? {
        thickness = t;
    }
    // A shell is thin: a thickness beyond 10× the sheet's size is no shell (and overflows).
    let size = mesh.bbox_diagonal();
    if let Some(f) = thickness.iter().position(|&h| h > 10.0 * size) {
        return Err(mesh.invalid(format!(
            "thickness {} m at face {f} is more than 10× the sheet's size ({size_h} m): \
             not a thin shell",
            crate::math::human(thickness[f]),
            size_h = crate::math::human(size)
        )));
    }
    if let Some(mu) = positive_face_field(
        mesh,
        "ref_shear_moduli",
        crate::settings::MAX_MODULUS,
        ("use_mesh_shear_modulus", m.use_mesh_shear_modulus),
    )? {
        young = mu.iter().map(|mu| 2.0 * mu * (1.0 + m.poisson)).collect();
    }
    let lame = young
        .iter()
        .map(|&e| Lame2d::from_young_poisson(e, m.poisson))
        .collect();

    Ok(FaceMaterial {
        thickness,
        young,
        lame,
    })
}

/// The rest state of the body.
struct RestStage {
    /// The rest forms at dial 0 and 1.
    rest: RestForms,
    /// The edge-DOF models' orientation signs, else empty.
    edge_sign: Vec<[Real; 3]>,
    /// The growth law's inputs.
    growth: GrowthInputs,
    /// The grown thickness ratio per face, empty unless the law scales it.
    grown_thickness: Vec<Real>,
}

/// The rest forms at dial 0 (the reference mesh's, in the bending model's own terms) and dial 1
/// (the target law's, then the growth law's, [`crate::rest::laws::targets`]).
fn rest_forms(
    mesh: &Mesh,
    topo: &Topology,
    settings: &Settings,
    thickness: &[Real],
    edge_normal: &[Option<crate::geometry::EdgeNormal>],
) -> Result<RestStage, MeshError> {
    let m = &settings.material;
    let mut rest = RestForms::no_growth(mesh, topo);
    let edge_sign = if m.bending.angle_variant().is_some() {
        edge_signs(topo)
    } else {
        Vec::new()
    };
    if let Some(variant) = m.bending.angle_variant() {
        // The reference curvature in the edge-DOF model's own terms (φ = 0), so that a curved
        // input mesh is stress-free under "no growth" for the tan variant too (sin at φ = 0
        // is the average).
        let b0 = midedge_angle_reference_b(mesh, topo, variant, edge_normal);
        rest.bbar1.clone_from(&b0);
        rest.bbar0 = b0;
    }
    let relaxed = stored_forms(mesh, topo, settings, edge_normal)?;
    let (growth, grown_thickness) =
        crate::rest::laws::targets(&mut rest, mesh, settings, thickness, relaxed)?;
    Ok(RestStage {
        rest,
        edge_sign,
        growth,
        grown_thickness,
    })
}

/// The forms `(â, b̂)` of the shape stored in the vertex field `original_positions`, in the
/// bending model's own terms, for a growth law that relaxes toward them
/// ([`crate::rest::laws::RestLaw::needs_stored_state`]); empty for other laws. Errors name the
/// field, a non-finite vertex or a degenerate face.
fn stored_forms(
    mesh: &Mesh,
    topo: &Topology,
    settings: &Settings,
    edge_normal: &[Option<crate::geometry::EdgeNormal>],
) -> Result<Vec<(Sym2, Sym2)>, MeshError> {
    let law = crate::rest::laws::law(&settings.growth.model());
    if !law.is_some_and(|l| l.needs_stored_state()) {
        return Ok(Vec::new());
    }
    let field = mesh.vertex_field("original_positions", 3)?.ok_or_else(|| {
        mesh.invalid(format!(
            "growth.law = \"{}\" needs its stored state: the vertex field \
             'original_positions' (3 components), the sheet's shape before it was creased, \
             with the mesh's connectivity",
            settings.growth.law.name()
        ))
    })?;
    let mut original = mesh.clone();
    for (v, p) in original.positions.iter_mut().enumerate() {
        let x = field.get(v);
        if !x
            .iter()
            .all(|c| c.is_finite() && c.abs() <= crate::mesh::MAX_COORDINATE)
        {
            return Err(mesh.invalid(format!(
                "vertex field 'original_positions' at vertex {v} is {x:?}: it must be finite \
                 coordinates"
            )));
        }
        *p = Vec3::new(x[0], x[1], x[2]);
    }
    let (a, mut b) = crate::rest::mesh_forms(&original.positions, &original, topo);
    if let Some(variant) = settings.material.bending.angle_variant() {
        b = midedge_angle_reference_b(&original, topo, variant, edge_normal);
    }
    if let Some(f) = a
        .iter()
        .position(|a| !(a[0] > 0.0 && crate::math::sym_det(a) > 0.0))
    {
        return Err(mesh.invalid(format!(
            "vertex field 'original_positions': face {f} is degenerate in the stored shape"
        )));
    }
    Ok(a.into_iter().zip(b).collect())
}

/// Lumped mass per vertex: Σ ρ h A / 3 over its faces, reference areas (kg).
fn lumped_masses(mesh: &Mesh, thickness: &[Real], density: Real) -> Vec<Real> {
    let nv = mesh.positions.len();
    let mut mass = vec![0.0; nv];
    for (f, face) in mesh.faces.iter().enumerate() {
        let area = mesh.face_area(f);
        let mf = density * thickness[f] * area / 3.0;
        for &v in face {
            mass[v] += mf;
        }
    }

    mass
}

/// How far from a symmetry plane a vertex may lie and be on it, relative to the mesh's
/// bounding-box diagonal (meshes cut at a plane put their vertices on it to round-off).
const SYMMETRY_TOLERANCE: Real = 1e-9;

/// What `[constraints]` holds.
struct Supports {
    /// True for held vertices (unused ones, indicators, tags, boxes, clamp rings, paths).
    fixed: Vec<bool>,
    /// The boundary edges whose rotation is held or set.
    clamped_edges: Vec<usize>,
    /// Per edge, its set mid-edge normal (empty when none).
    edge_normal: Vec<Option<crate::geometry::EdgeNormal>>,
    /// Vertices on prescribed paths, their displacement at dial 1 (m) and the components that
    /// follow it.
    prescribed: Vec<(usize, Vec3, [bool; 3])>,
    /// Per vertex, the coordinate components held by component supports, symmetry planes
    /// along an axis and partial paths.
    comp: Vec<[bool; 3]>,
    /// Per vertex, the directions off the axes that oblique symmetry planes hold, with the
    /// index of their support in `groups`.
    dirs: Vec<Vec<hold::Held>>,
    /// Every support, with the DOFs it holds.
    groups: Vec<SupportGroup>,
}

/// One support of `[constraints]` (a key, or one entry of a list) and the position DOFs it
/// holds (`3v + k`, vertex `v`, component `k`), for its reaction. A DOF held by two supports
/// belongs to the first, in the order of the settings reference.
#[derive(Clone, Debug, PartialEq)]
pub struct SupportGroup {
    /// The settings key, e.g. `fix_boxes[0]`, `clamp[1]`, `support[0]`.
    pub name: String,
    /// The held DOFs, ascending.
    pub dofs: Vec<usize>,
    /// The held directions off the coordinate axes, as (vertex, unit direction): an oblique
    /// symmetry plane's, the automatic rigid pins', and every held component of a vertex that
    /// also has one ([`hold::finalise`]).
    pub directions: Vec<(usize, Vec3)>,
}

/// The supports of `[constraints]` on `mesh`, with the unused vertices held. Errors name the key
/// that selects nothing or a vertex given two constraints.
fn supports(
    mesh: &Mesh,
    topo: &Topology,
    settings: &Settings,
    is_unused: &[bool],
) -> Result<Supports, MeshError> {
    use crate::geometry::EdgeNormal;
    let c = &settings.constraints;
    let bending = settings.material.bending;
    // The edge-DOF models set a boundary edge's mid-edge normal in space.
    let angle = bending.angle_variant().is_some();
    let nv = mesh.positions.len();
    let mut edge_normal: Vec<Option<EdgeNormal>> = Vec::new();
    let mut set_normal = |e: usize, en: EdgeNormal| {
        if edge_normal.is_empty() {
            edge_normal = vec![None; topo.edges.len()];
        }
        if edge_normal[e].is_none() {
            edge_normal[e] = Some(en);
        }
    };
    // A boundary edge's face, the edge's local index there (opposite vertex), and its unit
    // reference normal.
    let face_of = |e: usize| {
        let f = topo.edge_faces[e][0];
        let fv = mesh.faces[f];
        let i = (0..3)
            .find(|&i| !topo.edges[e].contains(&fv[i]))
            .unwrap_or(0);
        let [a, b, c] = mesh.face_positions(f);
        (f, i, (b - a).cross(&(c - a)).normalize())
    };
    let mut fixed: Vec<bool> = is_unused.to_vec();
    // Which DOF each support holds, in order; `claimed` keeps a DOF in its first support.
    let mut groups: Vec<SupportGroup> = Vec::new();
    let mut claimed = vec![false; 3 * nv];
    let mut group = |name: String, dofs: &mut dyn Iterator<Item = usize>| {
        let mut d: Vec<usize> = dofs.filter(|&d| !is_unused[d / 3]).collect();
        d.sort_unstable();
        d.dedup();
        d.retain(|&k| !std::mem::replace(&mut claimed[k], true));
        groups.push(SupportGroup {
            name,
            dofs: d,
            directions: Vec::new(),
        });
        groups.len() - 1
    };
    let all3 = |v: usize| 3 * v..3 * v + 3;
    if c.use_constraint_indicators {
        if let Some(ci) = mesh.vertex_field("constraint_indicators", 1)? {
            let on: Vec<usize> = (0..nv).filter(|&v| ci.data[v] != 0.0).collect();
            for &v in &on {
                fixed[v] = true;
            }
            if !on.is_empty() {
                group(
                    "constraint_indicators".into(),
                    &mut on.iter().flat_map(|&v| all3(v)),
                );
            }
        }
    }
    if !c.fix_tags.is_empty() {
        let tags = mesh.vertex_field("node_tags", 1)?.ok_or_else(|| {
            mesh.invalid("constraints.fix_tags needs the per-vertex field 'node_tags'")
        })?;
        // A tag that fixes nothing is a mistake (a load selecting nothing is one too).
        for (i, &tag) in c.fix_tags.iter().enumerate() {
            if !tags.data.iter().any(|&t| t.round() as i64 == tag) {
                return Err(mesh.invalid(format!(
                    "constraints.fix_tags[{i}] = {tag} selects no vertex: no value of \
                     'node_tags' is {tag}"
                )));
            }
        }
        let on: Vec<usize> = (0..nv)
            .filter(|&v| c.fix_tags.contains(&(tags.data[v].round() as i64)))
            .collect();
        for &v in &on {
            fixed[v] = true;
        }
        group("fix_tags".into(), &mut on.iter().flat_map(|&v| all3(v)));
    }
    for (i, b) in c.fix_boxes.iter().enumerate() {
        let on: Vec<usize> = (0..nv)
            .filter(|&v| {
                let p = mesh.positions[v];
                (0..3).all(|k| p[k] >= b.min[k] && p[k] <= b.max[k])
            })
            .collect();
        if on.is_empty() {
            return Err(mesh.invalid(format!(
                "constraints.fix_boxes[{i}] (min {:?}, max {:?}) selects no vertex",
                b.min, b.max
            )));
        }
        for &v in &on {
            fixed[v] = true;
        }
        group(
            format!("fix_boxes[{i}]"),
            &mut on.iter().flat_map(|&v| all3(v)),
        );
    }
    let mut clamped_edges = Vec::new();
    for (i, sel) in c.clamp.iter().enumerate() {
        let what = format!("constraints.clamp[{i}]");
        let mut on = vec![false; nv];
        for v in select::select_vertices(mesh, sel, &what)? {
            on[v] = true;
        }
        let before = clamped_edges.len();
        for (e, ends) in topo.edges.iter().enumerate() {
            let ef = topo.edge_faces[e];
            if ef[1] == crate::mesh::topology::NONE && on[ends[0]] && on[ends[1]] {
                clamped_edges.push(e);
            }
        }
        // The clamped boundary vertices are held. With edge DOFs the boundary edges' mid-edge
        // normals keep their reference direction, which holds the boundary's rotation on the
        // boundary line itself; otherwise their edge neighbours (one ring) are held too, so the
        // first row of faces stays rigid.
        let mut ring = vec![false; nv];
        for &e in &clamped_edges[before..] {
            for v in topo.edges[e] {
                ring[v] = true;
            }
            if angle {
                set_normal(e, EdgeNormal::Fixed(face_of(e).2));
            }
        }
        let mut held = ring.clone();
        if !angle {
            for ends in &topo.edges {
                if ring[ends[0]] || ring[ends[1]] {
                    held[ends[0]] = true;
                    held[ends[1]] = true;
                }
            }
        }
        if clamped_edges.len() == before {
            return Err(mesh.invalid(format!(
                "{what} selects no boundary edge: a clamp acts on a boundary, and both ends of \
                 a boundary edge must be selected"
            )));
        }
        for v in 0..nv {
            fixed[v] |= held[v];
        }
        group(
            format!("clamp[{i}]"),
            &mut (0..nv).filter(|&v| held[v]).flat_map(all3),
        );
    }
    // Components held by supports, per vertex.
    let mut comp = vec![[false; 3]; nv];
    for (i, sp) in c.support.iter().enumerate() {
        let what = format!("constraints.support[{i}]");
        let mask = crate::config::constraints::component_mask(Some(&sp.components));
        let on = select::select_vertices(mesh, &sp.on, &what)?;
        for &v in &on {
            for k in 0..3 {
                comp[v][k] |= mask[k];
            }
        }
        group(
            format!("support[{i}]"),
            &mut on
                .iter()
                .flat_map(|&v| (0..3).filter(|&k| mask[k]).map(move |k| 3 * v + k)),
        );
    }
    // Symmetry planes: the normal component held on the plane, and the boundary edges on it
    // keep their mid-edge normal in the plane.
    let tol = SYMMETRY_TOLERANCE * mesh.bbox_diagonal();
    let mut dirs: Vec<Vec<hold::Held>> = vec![Vec::new(); nv];
    for (i, sy) in c.symmetry.iter().enumerate() {
        let what = format!("constraints.symmetry[{i}]");
        let normal = sy.unit_normal();
        let plane = sy.describe();
        let on: Vec<bool> = (0..nv)
            .map(|v| !is_unused[v] && (normal.dot(&mesh.positions[v]) - sy.at).abs() <= tol)
            .collect();
        if !on.contains(&true) {
            return Err(mesh.invalid(format!(
                "{what}: no vertex lies on the plane {plane} (within {} m, 1e-9 of the \
                 mesh's size); a symmetry plane cuts the model along its boundary",
                crate::math::human(tol)
            )));
        }
        if matches!(
            bending,
            crate::settings::BendingModel::PatchFit | crate::settings::BendingModel::MidedgeAverage
        ) {
            return Err(mesh.invalid(format!(
                "{what}: mirror symmetry sets the boundary's rotation (the surface meets the \
                 plane at a right angle), which needs a bending model with edge rotations \
                 (material.bending = \"midedge_sin\" or \"midedge_tan\"); with {bending:?} \
                 hold the normal component with [[constraints.support]] and model the whole"
            )));
        }
        let mut edges = 0usize;
        for (e, ends) in topo.edges.iter().enumerate() {
            if topo.edge_faces[e][1] != crate::mesh::topology::NONE || !on[ends[0]] || !on[ends[1]]
            {
                continue;
            }
            edges += 1;
            if !angle {
                continue;
            }
            let (f, li, nf) = face_of(e);
            let fv = mesh.faces[f];
            let ev = mesh.positions[fv[(li + 2) % 3]] - mesh.positions[fv[(li + 1) % 3]];
            let t = normal.cross(&ev).normalize();
            let cos = t.dot(&nf);
            if cos.abs() < 0.1 {
                return Err(mesh.invalid(format!(
                    "{what}: face {f} meets the plane {plane} at {:.1}° from the plane \
                     itself; a mirror-symmetric surface crosses its plane (at 90° in the \
                     limit of a fine mesh)",
                    cos.abs().asin().to_degrees()
                )));
            }
            set_normal(
                e,
                EdgeNormal::Plane {
                    normal,
                    sign: cos.signum(),
                },
            );
            clamped_edges.push(e);
        }
        if angle && edges == 0 {
            return Err(mesh.invalid(format!(
                "{what}: no boundary edge lies on the plane {plane}; a symmetry plane cuts the \
                 model along its boundary"
            )));
        }
        let list: Vec<usize> = (0..nv).filter(|&v| on[v]).collect();
        match sy.coordinate_axis() {
            Some(axis) => {
                let k = axis.index();
                for &v in &list {
                    comp[v][k] = true;
                }
                group(
                    format!("symmetry[{i}]"),
                    &mut list.iter().map(|&v| 3 * v + k),
                );
            }
            None => {
                let gi = group(format!("symmetry[{i}]"), &mut std::iter::empty());
                for &v in &list {
                    dirs[v].push((normal, gi));
                }
            }
        }
    }
    let mut prescribed: Vec<(usize, Vec3, [bool; 3])> = Vec::new();
    for (i, pd) in c.displacement.iter().enumerate() {
        let what = format!("constraints.displacement[{i}]");
        let mask = crate::config::constraints::component_mask(pd.components.as_deref());
        let on = select::select_vertices(mesh, &pd.on, &what)?;
        for &v in &on {
            if fixed[v] || prescribed.iter().any(|&(u, _, _)| u == v) {
                return Err(mesh.invalid(format!(
                    "{what}: vertex {v} is already fixed or given another prescribed path; a \
                     vertex is either held, or moved along one path"
                )));
            }
            if !dirs[v].is_empty() {
                return Err(mesh.invalid(format!(
                    "{what}: vertex {v} lies on an oblique symmetry plane \
                     (constraints.symmetry), which holds its normal component; a vertex on \
                     such a plane is not given a path"
                )));
            }
            if let Some(k) = (0..3).find(|&k| mask[k] && comp[v][k]) {
                return Err(mesh.invalid(format!(
                    "{what}: vertex {v}'s {} component is also held by a support \
                     (constraints.support or constraints.symmetry); a component is either \
                     held, or moved along a path",
                    ["x", "y", "z"][k]
                )));
            }
            prescribed.push((v, Vec3::from(pd.displacement), mask));
        }
        group(
            format!("displacement[{i}]"),
            &mut on
                .iter()
                .flat_map(|&v| (0..3).filter(|&k| mask[k]).map(move |k| 3 * v + k)),
        );
    }
    for &(v, _, mask) in &prescribed {
        for k in 0..3 {
            comp[v][k] |= mask[k];
        }
    }
    // A vertex with its three components held is a held vertex.
    for v in 0..nv {
        if comp[v] == [true; 3] {
            fixed[v] = true;
        }
    }

    Ok(Supports {
        fixed,
        clamped_edges,
        edge_normal,
        prescribed,
        comp,
        dirs,
        groups,
    })
}

/// Rejects the settings under which a `free` sheet (nothing held) has no equilibrium for the
/// static solver: gravity without obstacles, loads with only finite obstacles, a ground.
fn check_posed(mesh: &Mesh, settings: &Settings, free: bool) -> Result<(), MeshError> {
    let gravity = settings.loads.gravity.iter().any(|&g| g != 0.0);
    let obstacles = !settings.obstacles.is_empty();
    if free && gravity && !obstacles && settings.solver.mode == crate::settings::Mode::Static {
        return Err(mesh.invalid(
            "static mode under gravity (loads.gravity) needs fixed vertices: a free sheet has no \
             equilibrium. Fix some (constraint_indicators, constraints.fix_tags or \
             constraints.fix_boxes) or use solver.mode = \"dynamic\"",
        ));
    }
    // A mesh obstacle bounds every Newton step by continuous collision detection: the sheet
    // cannot pass through it, even on the unbounded first step of a free sheet.
    let on_plane = settings.obstacles.iter().any(|o| {
        matches!(
            o.shape,
            Some(
                crate::config::obstacle::ShapeKind::Plane
                    | crate::config::obstacle::ShapeKind::Mesh
            )
        )
    });
    let pressed = settings.obstacles.iter().any(|o| o.force.is_some());
    if free
        && obstacles
        && !on_plane
        && (gravity || settings.loads.any_external() || pressed)
        && settings.solver.mode == crate::settings::Mode::Static
    {
        return Err(mesh.invalid(
            "obstacles: a free sheet under loads in static mode can rest only on a plane \
             or mesh obstacle: Newton's first step of a free sheet is unbounded and can carry \
             it through a finite analytic obstacle (a sphere, capsule, cylinder or box). Add a \
             plane, fix \
             some vertices, or use solver.mode = \"dynamic\"",
        ));
    }
    if settings.contact.enabled && free && settings.solver.mode == crate::settings::Mode::Static {
        return Err(mesh.invalid(
            "static mode with a ground (contact.enabled) needs fixed vertices: a free sheet on \
             a frictionless plane slides and spins freely. Fix some vertices or use \
             solver.mode = \"dynamic\"",
        ));
    }
    Ok(())
}

/// First and second fundamental forms of every face under an edge-DOF bending model, at
/// positions `x` and edge DOFs `phi`.
fn midedge_angle_forms(
    body: &Body,
    variant: crate::config::shell::AngleVariant,
    x: &[Vec3],
    phi: &[Real],
) -> (Vec<Sym2>, Vec<Sym2>) {
    (0..body.num_faces())
        .map(|f| {
            let (xs, has) = midedge_stencil(&body.mesh, &body.topo, x, f);
            let ph = body.topo.face_edges[f].map(|e| phi[e]);
            (
                crate::geometry::first_fundamental_form(&[xs[0], xs[1], xs[2]]),
                crate::geometry::midedge_angle_b(
                    &xs,
                    has,
                    &ph,
                    body.edge_sign[f],
                    set_normals(&body.edge_normal, &body.topo, f),
                    variant,
                ),
            )
        })
        .unzip()
}

/// Each face's second fundamental form on the reference mesh under an edge-DOF bending model
/// with every edge DOF at zero (the orientation signs then play no part), and the boundary
/// edges' mid-edge normals set where `edge_normal` sets them (a symmetry plane's: the
/// reference shape is its rest shape with the mirror condition).
fn midedge_angle_reference_b(
    mesh: &Mesh,
    topo: &Topology,
    variant: crate::config::shell::AngleVariant,
    edge_normal: &[Option<crate::geometry::EdgeNormal>],
) -> Vec<Sym2> {
    (0..mesh.faces.len())
        .map(|f| {
            let (xs, has) = midedge_stencil(mesh, topo, &mesh.positions, f);
            let set = set_normals(edge_normal, topo, f);
            crate::geometry::midedge_angle_b(&xs, has, &[0.0; 3], [1.0; 3], set, variant)
        })
        .collect()
}

/// The set mid-edge normals of face `f`'s edges (opposite `v0, v1, v2`).
fn set_normals(
    edge_normal: &[Option<crate::geometry::EdgeNormal>],
    topo: &Topology,
    f: usize,
) -> [Option<crate::geometry::EdgeNormal>; 3] {
    if edge_normal.is_empty() {
        [None; 3]
    } else {
        topo.face_edges[f].map(|e| edge_normal[e])
    }
}

/// Face `f`'s mid-edge stencil at positions `x`: its 3 vertices, then the far vertex across
/// each edge (the face's first vertex stands in across a boundary edge), and whether each edge
/// has a neighbour.
pub fn midedge_stencil(
    mesh: &Mesh,
    topo: &Topology,
    x: &[Vec3],
    f: usize,
) -> ([Vec3; 6], [bool; 3]) {
    let face = mesh.faces[f];
    let o = topo.opposite_vertex[f];
    let has = o.map(|v| v != crate::mesh::topology::NONE);
    let xs = [0, 1, 2, 3, 4, 5].map(|k| match k {
        0..=2 => x[face[k]],
        _ if has[k - 3] => x[o[k - 3]],
        _ => x[face[0]],
    });
    (xs, has)
}

/// Each face's orientation sign on its three edges: +1 for the edge's first face, −1 for its
/// second.
fn edge_signs(topo: &Topology) -> Vec<[Real; 3]> {
    topo.face_edges
        .iter()
        .enumerate()
        .map(|(f, fe)| {
            fe.map(|e| {
                if topo.edge_faces[e][0] == f {
                    1.0
                } else {
                    -1.0
                }
            })
        })
        .collect()
}

/// The faces of a moisture boundary region: those whose `tri_tags` value is in `b.tags` (all
/// faces when empty) and, if `b.inside` is given, whose reference centroid lies in that box.
pub fn region_faces(
    mesh: &Mesh,
    b: &crate::settings::MoistureBoundary,
) -> Result<Vec<usize>, MeshError> {
    select::faces_matching(mesh, &b.tags, b.inside.as_ref(), "moisture.boundary")
}

/// Rejects moisture boundary regions that give one face side two different conditions.
fn check_moisture_regions(mesh: &Mesh, settings: &Settings) -> Result<(), MeshError> {
    let mut seen: std::collections::HashMap<(usize, crate::settings::SurfaceSide), usize> =
        Default::default();
    for (i, b) in settings.moisture.boundary.iter().enumerate() {
        for f in region_faces(mesh, b)? {
            if let Some(&j) = seen.get(&(f, b.side)) {
                let o = &settings.moisture.boundary[j];
                if (o.kind, o.value, o.k, o.ambient) != (b.kind, b.value, b.k, b.ambient) {
                    return Err(mesh.invalid(format!(
                        "moisture.boundary[{j}] and moisture.boundary[{i}] both set the {:?} \
                         surface of face {f} to different conditions",
                        b.side
                    )));
                }
            }
            seen.insert((f, b.side), i);
        }
    }
    Ok(())
}

/// Rejects temperature boundary regions that give one face side two different conditions at
/// the same time: two permanent ones, two windowed ones whose windows overlap, or a windowed one
/// over a prescribed temperature (a windowed flux or Robin condition otherwise replaces the
/// side's permanent one while it is open).
fn check_heat_regions(mesh: &Mesh, settings: &Settings) -> Result<(), MeshError> {
    let bs = &settings.temperature.boundary;
    let faces: Vec<Vec<usize>> = bs
        .iter()
        .enumerate()
        .map(|(i, b)| {
            select::faces_matching(
                mesh,
                &b.tags,
                b.inside.as_ref(),
                &format!("temperature.boundary[{i}]"),
            )
        })
        .collect::<Result<_, _>>()?;
    for (i, a) in bs.iter().enumerate() {
        for (j, b) in bs.iter().enumerate().skip(i + 1) {
            let (ua, ub) = (
                a.until.unwrap_or(Real::INFINITY),
                b.until.unwrap_or(Real::INFINITY),
            );
            let same = (a.kind, a.value, a.h, a.ambient) == (b.kind, b.value, b.h, b.ambient);
            // A windowed condition replaces a permanent one while it is open, unless that one
            // is a prescribed temperature.
            let value = |c: &crate::config::temperature::HeatBoundary| {
                c.kind == crate::settings::SurfaceKind::Value
            };
            let overrides = a.permanent() != b.permanent() && !value(a) && !value(b);
            if a.side != b.side || same || overrides || ua <= b.from || ub <= a.from {
                continue;
            }
            let set: std::collections::HashSet<usize> = faces[i].iter().copied().collect();
            if let Some(f) = faces[j].iter().find(|f| set.contains(f)) {
                return Err(mesh.invalid(format!(
                    "temperature.boundary[{i}] and temperature.boundary[{j}] both set the {:?} \
                     surface of face {f} to different conditions at the same time",
                    b.side
                )));
            }
        }
    }
    Ok(())
}

/// What a contact penalty on the sheet's surfaces needs per vertex, and its defaults: the
/// reference area `A_v` (one third of its faces', m²), the half thickness `h_v/2` (the mean of
/// its faces', area-weighted, m), and over the sheet the area-weighted means of E/h (Pa/m, the
/// default stiffness) and of h (m; the default smoothing is a hundredth of it).
pub struct ContactAreas {
    /// `A_v` (m²).
    pub area: Vec<Real>,
    /// `h_v/2` (m).
    pub half_thickness: Vec<Real>,
    /// Area-weighted mean of E/h (Pa/m).
    pub e_over_h: Real,
    /// Area-weighted mean thickness (m).
    pub h_mean: Real,
}

impl ContactAreas {
    /// The contact data of `mesh` with per-face `thickness` and `young` (Pa).
    pub fn of(mesh: &Mesh, thickness: &[Real], young: &[Real]) -> ContactAreas {
        let nv = mesh.positions.len();
        let mut area = vec![0.0; nv];
        let mut h_area = vec![0.0; nv];
        let (mut total, mut e_over_h, mut h_mean) = (0.0, 0.0, 0.0);
        for (f, face) in mesh.faces.iter().enumerate() {
            let a = mesh.face_area(f);
            total += a;
            e_over_h += a * young[f] / thickness[f];
            h_mean += a * thickness[f];
            for &v in face {
                area[v] += a / 3.0;
                h_area[v] += a / 3.0 * thickness[f];
            }
        }
        let total = total.max(Real::MIN_POSITIVE);
        let half_thickness = (0..nv)
            .map(|v| {
                if area[v] > 0.0 {
                    0.5 * h_area[v] / area[v]
                } else {
                    0.0
                }
            })
            .collect();
        ContactAreas {
            area,
            half_thickness,
            e_over_h: e_over_h / total,
            h_mean: h_mean / total,
        }
    }
}

/// The ground of `[contact]` with the per-vertex areas and half thicknesses it needs (see
/// [`crate::contact`] and [`ContactAreas`]); `"auto"` stiffness is the area-weighted
/// mean of E/h, `"auto"` smoothing is the area-weighted mean h over 100. A vertex that starts
/// deeper inside than the smoothing is an error naming it.
fn build_ground(
    mesh: &Mesh,
    c: &crate::settings::Contact,
    thickness: &[Real],
    young: &[Real],
) -> Result<crate::contact::Ground, MeshError> {
    let ContactAreas {
        area,
        half_thickness,
        e_over_h,
        h_mean,
    } = ContactAreas::of(mesh, thickness, young);
    let g = crate::contact::Ground {
        point: Vec3::from(c.point),
        normal: Vec3::from(c.normal).normalize(),
        stiffness: c.stiffness.or(e_over_h),
        smoothing: c.smoothing.or(h_mean / 100.0),
        friction: c.friction,
        slip_speed: c.slip_speed,
        area,
        half_thickness,
    };
    // A start deep inside the ground would be thrown out by the penalty's full force.
    for (v, x) in mesh.positions.iter().enumerate() {
        let p = g.penetration(v, x);
        if g.area[v] > 0.0 && p > g.smoothing {
            return Err(mesh.invalid(format!(
                "vertex {v} starts {p_h} m inside the ground (its surface, mid-surface \
                 − h/2, is below the plane through contact.point with contact.normal); \
                 move the plane or the mesh",
                p_h = crate::math::human(p)
            )));
        }
    }
    Ok(g)
}

fn unused_mask(nv: usize, unused: &[usize]) -> Vec<bool> {
    let mut m = vec![false; nv];
    for &u in unused {
        m[u] = true;
    }
    m
}
