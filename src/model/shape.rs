//! The two element worlds of the cell model: what changes with the dimension `D` and the
//! element of `N` nodes (`E = D·N` unknowns), everything else being written once.
//!
//! - [`HalfPlane`]: six-node triangles on the half cell's [`Mesh`], the substrate's
//!   section [`Substrate`]; the plane-strain and the axisymmetric models
//!   ([`crate::physics::KinematicModel`], chosen once per element loop).
//! - [`Quarter`]: ten-node tetrahedra on the quarter cell's [`TetMesh`], the substrate on
//!   its pillar lattice [`LatticeSubstrate`]; the symmetry planes x = c_x and z = c_z.
//!
//! A shape names its mesh (which names its element's tabulation), its substrate and the
//! dual numbers of its tangents (`D + D² + 1` directions for the band forces, `D + 1` for
//! the adhesion rows), places the active strain and the symmetry, and sends the element
//! loops to the formulation of the case's kinematic model. The physics itself is written
//! once for every dimension ([`crate::physics`]).

use nalgebra::{Const, SMatrix, SVector, Vector2, Vector3};
use num_dual::DualSVec64;

use super::history::LayerField;
use super::{CellOf, ModelParams};
use crate::dae::DaeError;
use crate::fem::{CellMesh, Domain, Mesh, TetMesh};
use crate::physics::{ActiveStrain, Fibre, KinematicModel, LatticeSubstrate, Real, Substrate};

/// Largest number of dual directions a tangent uses (3-D band forces: 3 + 9 + 1).
pub const MAX_DIRECTIONS: usize = 13;

/// A dual number seeded along one direction, whose gradient can be read back.
pub trait Seeded: Real + Send + Sync {
    /// `re` with derivative 1 along `direction`.
    fn seeded(re: f64, direction: usize) -> Self;
    /// `re` with no derivative.
    fn constant(re: f64) -> Self;
    /// The derivatives along every direction (0 beyond the type's own).
    fn gradient(&self) -> [f64; MAX_DIRECTIONS];
}

impl<const M: usize> Seeded for DualSVec64<M> {
    #[inline(always)]
    fn seeded(re: f64, direction: usize) -> Self {
        Self::from_re(re).derivative(direction)
    }

    #[inline(always)]
    fn constant(re: f64) -> Self {
        Self::from_re(re)
    }

    #[inline(always)]
    fn gradient(&self) -> [f64; MAX_DIRECTIONS] {
        let g = self.eps.unwrap_generic(Const::<M>, Const::<1>);
        std::array::from_fn(|k| if k < M { g[k] } else { 0.0 })
    }
}

/// Which displacement components the symmetry eliminates in the 3-D quarter cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Constraints {
    /// The quarter cell: u_x = 0 on the mesh's plane x = c_x, u_z = 0 on z = c_z (in the
    /// half-plane models: u_x = 0 on the symmetry line).
    #[default]
    Quarter,
    /// The slab check: u_x = 0 on x = c_x and u_z = 0 on every node (plane strain on a
    /// one-layer 3-D mesh).
    Slab,
}

/// What the cell model takes from its dimension and element (module documentation).
pub trait Shape<const D: usize, const N: usize, const E: usize>:
    Sized + Send + Sync + 'static
{
    /// The mesh.
    type Mesh: CellMesh<D, N>;
    /// The substrate, evaluated at positions in `D` dimensions.
    type Substrate: LayerField<D> + Send + Sync + PartialEq;
    /// Dual numbers of the band tangent: x (D), F (D²), μ_as (1).
    #[doc(hidden)]
    type BandDual: Seeded;
    /// Dual numbers of the adhesion row's tangent: x (D), μ_as (1).
    #[doc(hidden)]
    type RateDual: Seeded;
    /// Whether the band kernel checks `det F > 0` at every band point of an element in
    /// reach, also where the band is zero (then it skips the force), or skips those points
    /// unchecked. Checking catches an element turned inside out between the standard
    /// points (`cases/hard/e-09.ron` stops on it at t = 47 119 s; unchecked, the run goes
    /// on to an unphysical state, the nucleus top 10 µm down). It costs 6.5 % of a 3-D
    /// run (paired runs of `cases/fast/push-pull-3d-coarse.ron` to 100 s, 2026-12-03: the
    /// tetrahedra's band rule has 120 points), nothing measurable in 2-D.
    const CHECK_EVERY_BAND_POINT: bool;

    /// The substrate of `p`.
    fn substrate(p: &ModelParams) -> Self::Substrate;
    /// The cell centre.
    fn center(p: &ModelParams) -> SVector<f64, D>;
    /// The active strain `F_a` at `t_a = 1` at reference point `x` of `domain`, about the
    /// centre `c`.
    fn active_tensor(
        act: &ActiveStrain,
        x: &[f64; D],
        c: &SVector<f64, D>,
        domain: Domain,
    ) -> SMatrix<f64, D, D>;
    /// The fibre families (MODEL.md §11) at reference point `x`, about the centre `c`:
    /// the PAC's along `T`, the bottom region's along `N`, each with its indicator.
    fn fibres(act: &ActiveStrain, x: &[f64; D], c: &SVector<f64, D>) -> [Fibre<D>; 2];
    /// Whether component `c` of node `i` is eliminated by the symmetry, per node.
    fn eliminated(mesh: &Self::Mesh, constraints: Constraints) -> Vec<[bool; D]>;
    /// The nodes on a diagonal mirror plane, whose last component is tied to the first
    /// (u_z = u_x on the 3-D eighth cell's plane x − c_x = z − c_z).
    fn tied(_mesh: &Self::Mesh) -> &[usize] {
        &[]
    }
    /// The nodes of the outer surface in order along it, the cell on the left, where the
    /// model keeps that surface from passing through itself (`super::self_contact`);
    /// empty where it does not (3-D).
    fn outline(_mesh: &Self::Mesh) -> Vec<usize> {
        Vec::new()
    }
    /// The contact radius in state `y`: the length of the contour in contact in the plane
    /// z = 0, `(deformed, reference)` \[µm\].
    fn contact_lengths(cell: &CellOf<Self, D, N, E>, y: &[f64]) -> (f64, f64);
    /// The adhered reference radius and its rate in state (`y`, `yp`) [µm, µm/s]
    /// ([`super::events`]).
    fn adhered_radius(cell: &CellOf<Self, D, N, E>, y: &[f64], yp: &[f64]) -> (f64, f64);
    /// The residual or the iteration matrix with the formulation of the case's kinematic
    /// model.
    fn evaluate(cell: &mut CellOf<Self, D, N, E>, what: Evaluation) -> Result<(), DaeError>;
}

pub use crate::dae::State;

/// The element tabulation of shape `S`'s mesh.
pub(crate) type TabOf<S, const D: usize, const N: usize, const E: usize> =
    <<S as Shape<D, N, E>>::Mesh as CellMesh<D, N>>::Tab;

/// One evaluation of the cell's DAE.
pub enum Evaluation<'a> {
    /// The residual `F(t, y, ẏ)` into the slice.
    Residual(State<'a>, &'a mut [f64]),
    /// The iteration matrix `J = ∂F/∂y + cj ∂F/∂ẏ` for `cj` (the number) into the slice
    /// (the pattern's order).
    Jacobian(State<'a>, f64, &'a mut [f64]),
}

/// The half cell's six-node triangles (plane strain and axisymmetric).
#[derive(Debug, Clone, Copy)]
pub struct HalfPlane;

/// The quarter cell's ten-node tetrahedra (3-D).
#[derive(Debug, Clone, Copy)]
pub struct Quarter;

/// What a half-plane model says when asked to be the 3-D one.
pub(crate) const THREE_D: &str =
    "the half-plane mesh cannot carry the 3-D model (a QuarterCell on a TetMesh does)";

/// `nodes` marked in `out`: their component `c` is eliminated.
fn mark<const D: usize>(mut out: Vec<[bool; D]>, nodes: &[usize], c: usize) -> Vec<[bool; D]> {
    for &i in nodes {
        out[i][c] = true;
    }
    out
}

impl Shape<2, 6, 12> for HalfPlane {
    type Mesh = Mesh;
    type Substrate = Substrate;
    type BandDual = DualSVec64<7>;
    type RateDual = DualSVec64<3>;
    const CHECK_EVERY_BAND_POINT: bool = true;

    fn substrate(p: &ModelParams) -> Substrate {
        p.substrate
    }

    fn center(p: &ModelParams) -> Vector2<f64> {
        Vector2::new(p.center[0], p.center[1])
    }

    fn active_tensor(
        act: &ActiveStrain,
        x: &[f64; 2],
        _c: &Vector2<f64>,
        domain: Domain,
    ) -> SMatrix<f64, 2, 2> {
        act.fa(&Vector2::new(x[0], x[1]), domain, 1.0)
    }

    fn fibres(act: &ActiveStrain, x: &[f64; 2], _c: &Vector2<f64>) -> [Fibre<2>; 2] {
        act.fibres(&Vector2::new(x[0], x[1]))
    }

    /// u_x = 0 on the symmetry line.
    fn eliminated(mesh: &Mesh, _: Constraints) -> Vec<[bool; 2]> {
        mark(vec![[false; 2]; mesh.nodes.len()], &mesh.symmetry_nodes, 0)
    }

    fn adhered_radius(cell: &CellOf<Self, 2, 6, 12>, y: &[f64], yp: &[f64]) -> (f64, f64) {
        cell.adhered_radius(y, yp)
    }

    /// The outer edges' nodes, from the cell's bottom counter-clockwise to its top.
    fn outline(mesh: &Mesh) -> Vec<usize> {
        let mut nodes = Vec::with_capacity(2 * mesh.outer_edges.len() + 1);
        for (k, &[a, m, b]) in mesh.outer_edges.iter().enumerate() {
            if k == 0 {
                nodes.push(a);
            }
            nodes.extend([m, b]);
        }
        nodes
    }

    fn contact_lengths(cell: &CellOf<Self, 2, 6, 12>, y: &[f64]) -> (f64, f64) {
        cell.contact_lengths(y)
    }

    fn evaluate(cell: &mut CellOf<Self, 2, 6, 12>, what: Evaluation) -> Result<(), DaeError> {
        use super::kinematics::{Axisymmetric, PlaneStrain};
        match cell.params.kinematics {
            KinematicModel::PlaneStrain => cell.evaluate_with::<PlaneStrain>(what),
            KinematicModel::Axisymmetric => cell.evaluate_with::<Axisymmetric>(what),
            KinematicModel::ThreeD => Err(DaeError::Fatal(THREE_D.into())),
        }
    }
}

impl Shape<3, 10, 30> for Quarter {
    type Mesh = TetMesh;
    type Substrate = LatticeSubstrate;
    type BandDual = DualSVec64<13>;
    type RateDual = DualSVec64<4>;
    const CHECK_EVERY_BAND_POINT: bool = false;

    fn substrate(p: &ModelParams) -> LatticeSubstrate {
        LatticeSubstrate {
            plane: p.substrate,
            lattice: p.lattice,
        }
    }

    /// (c_x, c_y, 0).
    fn center(p: &ModelParams) -> Vector3<f64> {
        Vector3::new(p.center[0], p.center[1], 0.0)
    }

    fn active_tensor(
        act: &ActiveStrain,
        x: &[f64; 3],
        c: &Vector3<f64>,
        domain: Domain,
    ) -> SMatrix<f64, 3, 3> {
        act.fa_revolved(&Vector3::new(x[0], x[1], x[2]), c.z, domain, 1.0)
    }

    fn fibres(act: &ActiveStrain, x: &[f64; 3], c: &Vector3<f64>) -> [Fibre<3>; 2] {
        act.fibres_revolved(&Vector3::new(x[0], x[1], x[2]), c.z)
    }

    /// u_x = 0 on the plane x = c_x; u_z = 0 on z = c_z, or everywhere for the slab.
    fn eliminated(mesh: &TetMesh, constraints: Constraints) -> Vec<[bool; 3]> {
        let slab = constraints == Constraints::Slab;
        let out = mark(
            vec![[false, false, slab]; mesh.nodes.len()],
            &mesh.symmetry_x,
            0,
        );
        mark(out, &mesh.symmetry_z, 2)
    }

    fn tied(mesh: &TetMesh) -> &[usize] {
        &mesh.symmetry_diagonal
    }

    fn adhered_radius(cell: &CellOf<Self, 3, 10, 30>, y: &[f64], yp: &[f64]) -> (f64, f64) {
        cell.adhered_radius(y, yp)
    }

    fn contact_lengths(cell: &CellOf<Self, 3, 10, 30>, y: &[f64]) -> (f64, f64) {
        cell.meridian_contact_lengths(y)
    }

    fn evaluate(cell: &mut CellOf<Self, 3, 10, 30>, what: Evaluation) -> Result<(), DaeError> {
        cell.evaluate_with::<super::kinematics::ThreeD>(what)
    }
}
