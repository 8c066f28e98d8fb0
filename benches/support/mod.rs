//! The model and state the kernel benchmarks and the ordering example share: the default
//! scene's model (`cases/pillars-push-pull.ron`) at a mesh refinement, and the cell 0.5 µm
//! down in the pillars' contact band, smoothly deformed, with small rates.

use cellsim::case::Case;
use cellsim::dae::Dae;
use cellsim::fem::Mesh;
use cellsim::model::CellModel;
use cellsim::scene;

/// The default scene's model at mesh refinement `refine`, with or without inertia.
pub fn model(refine: f64, inertia: bool) -> CellModel {
    let file = format!("{}/cases/pillars-push-pull.ron", env!("CARGO_MANIFEST_DIR"));
    let mut case = Case::load(&file).unwrap();
    case.mesh.refine = refine;
    let mesh = Mesh::generate(&scene::mesh_params(&case)).unwrap();
    CellModel::new(scene::model_params(&case, &file, inertia).unwrap(), mesh).unwrap()
}

/// The cell 0.5 µm down (in the contact band), smoothly deformed; small rates.
pub fn state(m: &CellModel) -> (Vec<f64>, Vec<f64>) {
    let n = m.size();
    let (mut y, mut yp) = (vec![0.0; n], vec![0.0; n]);
    for (i, x) in m.mesh.nodes.iter().enumerate() {
        let du = [
            0.05 * (0.3 * x[1]).sin() * x[0] / 10.0,
            -0.5 + 0.04 * (0.25 * x[0]).cos(),
        ];
        for (k, &duk) in du.iter().enumerate() {
            let d = m.dofs.u[i][k];
            if d != usize::MAX {
                y[d] = duk;
                yp[d] = 1e-4 * duk;
            }
        }
    }
    let off = m.dofs.mu_offset();
    for k in 0..m.dofs.n_mu() {
        y[off + k] = 700.0;
        yp[off + k] = 0.1;
    }
    (y, yp)
}

thread_local! {
    static GIVEN: std::cell::RefCell<Vec<usize>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The permutation last stored in `GIVEN`, as an external ordering.
fn given(_: &cellsim::dae::Pattern) -> Result<Vec<usize>, cellsim::dae::linsolve::OrderingError> {
    Ok(GIVEN.with(|g| g.borrow().clone()))
}

/// nnz(L) + nnz(U) of faer's simplicial LU with the column permutation `perm` (the
/// structural fill of that ordering and faer's partial pivoting).
#[allow(dead_code)] // not every user of this module counts fill
pub fn fill(pattern: &cellsim::dae::Pattern, values: &[f64], perm: &[usize]) -> usize {
    use cellsim::dae::LinearSolver;
    use cellsim::dae::linsolve::{ColumnOrdering, FaerLu};
    use faer::sparse::linalg::SupernodalThreshold;
    GIVEN.with(|g| *g.borrow_mut() = perm.to_vec());
    let mut s = FaerLu::with_options(faer::Par::Seq, SupernodalThreshold::FORCE_SIMPLICIAL)
        .ordered_by(ColumnOrdering::External {
            name: "given",
            order: given,
        });
    s.analyse(pattern).unwrap();
    s.factorize(values).unwrap();
    s.factor_nnz().unwrap()
}
