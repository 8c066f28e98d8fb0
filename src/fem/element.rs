//! What a finite-element model needs of its mesh and of its element's shape functions,
//! written once for the six-node triangles of the half cell ([`super::Mesh`],
//! [`super::P2Tabulation`]) and the ten-node tetrahedra of the quarter cell
//! ([`super::Mesh3`], [`super::TetTabulation`]): `D` the spatial dimension, `N` the nodes
//! per element.

use super::p2::GeometryOf;
use super::{Domain, Mesh, Mesh3, NamedPoints, P2Error, P2Tabulation, TetError, TetTabulation};
use super::{TetRule, TriangleRule};

/// A conforming mesh of the cell: nodes, elements of `N` nodes, their domains and the
/// named points on the vertical axis.
pub trait CellMesh<const D: usize, const N: usize>: Clone + Send + Sync {
    /// Node coordinates (reference configuration, µm).
    fn nodes(&self) -> &[[f64; D]];
    /// Element connectivity.
    fn elements(&self) -> &[[usize; N]];
    /// Domain of each element.
    fn domains(&self) -> &[Domain];
    /// The named points on the vertical axis through the centre.
    fn points(&self) -> &NamedPoints;

    /// Whether each node belongs to an element of domain `d`.
    fn nodes_of_domain(&self, d: Domain) -> Vec<bool> {
        let mut on = vec![false; self.nodes().len()];
        for (el, &dom) in self.elements().iter().zip(self.domains()) {
            if dom == d {
                for &i in el {
                    on[i] = true;
                }
            }
        }
        on
    }

    /// The nodes of element `e`'s corners and mid-nodes, in its order.
    fn element_coords(&self, e: usize) -> [[f64; D]; N] {
        self.elements()[e].map(|i| self.nodes()[i])
    }
}

impl CellMesh<2, 6> for Mesh {
    fn nodes(&self) -> &[[f64; 2]] {
        &self.nodes
    }
    fn elements(&self) -> &[[usize; 6]] {
        &self.elements
    }
    fn domains(&self) -> &[Domain] {
        &self.domains
    }
    fn points(&self) -> &NamedPoints {
        &self.points
    }
}

impl CellMesh<3, 10> for Mesh3 {
    fn nodes(&self) -> &[[f64; 3]] {
        &self.nodes
    }
    fn elements(&self) -> &[[usize; 10]] {
        &self.elements
    }
    fn domains(&self) -> &[Domain] {
        &self.domains
    }
    fn points(&self) -> &NamedPoints {
        &self.points
    }
}

/// An element whose reference geometry is not valid: inverted or degenerate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElementGeometryError {
    /// A six-node triangle's.
    #[error(transparent)]
    Triangle(#[from] P2Error),
    /// A ten-node tetrahedron's.
    #[error(transparent)]
    Tetrahedron(#[from] TetError),
}

/// The element's shape functions tabulated at the points of a quadrature rule, and the
/// geometry of an element at those points.
pub trait ElementTabulation<const D: usize, const N: usize>: Send + Sync {
    /// The tabulation on the element's rule exact to `degree`, subdivided `levels` times
    /// (4 sub-triangles or 8 sub-tetrahedra per level).
    fn on_rule(degree: usize, levels: u32) -> Self;
    /// Shape-function values at each point.
    fn values(&self) -> &[[f64; N]];
    /// Number of points.
    fn len(&self) -> usize {
        self.values().len()
    }
    /// Whether the rule has no points.
    fn is_empty(&self) -> bool {
        self.values().is_empty()
    }
    /// Positions, weights times the Jacobian, and physical gradients at the points, for
    /// the element with nodes `x`.
    fn element_geometry(&self, x: &[[f64; D]; N])
    -> Result<GeometryOf<D, N>, ElementGeometryError>;
}

impl ElementTabulation<2, 6> for P2Tabulation {
    fn on_rule(degree: usize, levels: u32) -> Self {
        let rule = TriangleRule::degree(degree);
        P2Tabulation::new(&if levels == 0 {
            rule
        } else {
            rule.subdivided(levels)
        })
    }
    fn values(&self) -> &[[f64; 6]] {
        &self.values
    }
    fn element_geometry(
        &self,
        x: &[[f64; 2]; 6],
    ) -> Result<GeometryOf<2, 6>, ElementGeometryError> {
        Ok(self.geometry(x)?)
    }
}

impl ElementTabulation<3, 10> for TetTabulation {
    fn on_rule(degree: usize, levels: u32) -> Self {
        let rule = TetRule::degree(degree);
        TetTabulation::new(&if levels == 0 {
            rule
        } else {
            rule.subdivided(levels)
        })
    }
    fn values(&self) -> &[[f64; 10]] {
        &self.values
    }
    fn element_geometry(
        &self,
        x: &[[f64; 3]; 10],
    ) -> Result<GeometryOf<3, 10>, ElementGeometryError> {
        Ok(self.geometry(x)?)
    }
}
