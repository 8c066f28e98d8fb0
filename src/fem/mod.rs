//! Mesh, P2 elements, quadrature.
