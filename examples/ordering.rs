//! Fill-reducing orderings of the sparse LU on the cell model's own iteration matrices:
//! fill nnz(L) + nnz(U), symbolic analysis, numeric factorization and solve times per
//! ordering and backend, at several mesh refinements (the default scene's model,
//! `cases/pillars-push-pull.ron`, at the contact state of `benches/kernels.rs`).
//!
//! Without inertia (u, μ_as; cj = 0.1) every candidate; with inertia (u, v, μ_as;
//! cj = 100) the full-size LUs and the condensed one.
//!
//! `cargo run --release --example ordering [-- REFINE ...]` (default 0.5 1 2 4; set
//! `OPENBLAS_NUM_THREADS=1` for UMFPACK's BLAS), tab-separated, for
//! `scripts/bench_table.py --ordering FILE`. The
//! fill is deterministic: the structural nnz of faer's simplicial LU with each backend's
//! column permutation and faer's partial pivoting (KLU: its own count). The times are
//! medians over repetitions in which the backends take turns, so their ratios hold on a
//! shared machine.

use cellsim::dae::State;
use std::time::Instant;

use cellsim::dae::condensed::CondensedLu;
use cellsim::dae::linsolve::{ColumnOrdering, FaerLu, Permuted};
use cellsim::dae::{Dae, LinearSolver, Pattern};
use cellsim::solver::METIS_ORDERING;
use cellsim::sundials::{
    KluLu, UmfpackLu, UmfpackOrdering, nested_dissection, nested_dissection_ata,
};
use faer::Par;
use faer::sparse::linalg::SupernodalThreshold;

const T: f64 = 45_000.0;

#[path = "../benches/support/mod.rs"]
mod support;
use support::{fill, model, state};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

type FillFn = Box<dyn Fn(&Pattern, &[f64]) -> usize>;

struct Candidate {
    name: String,
    build: Box<dyn Fn() -> Box<dyn LinearSolver>>,
    /// nnz(L) + nnz(U) of this backend on a matrix, when it can tell.
    fill: Option<FillFn>,
}

fn faer_candidate(name: &str, make: fn() -> FaerLu) -> Candidate {
    Candidate {
        name: name.into(),
        build: Box::new(move || Box::new(make())),
        fill: Some(Box::new(move |p, v| {
            let mut s = make();
            s.analyse(p).unwrap();
            fill(p, v, s.column_permutation().unwrap())
        })),
    }
}

fn umfpack(o: UmfpackOrdering) -> Candidate {
    Candidate {
        name: UmfpackLu::new(o).name().into(),
        build: Box::new(move || Box::new(UmfpackLu::new(o))),
        fill: Some(Box::new(move |p, v| {
            let mut s = UmfpackLu::new(o);
            s.analyse(p).unwrap();
            s.factorize(v).unwrap();
            s.factor_nnz().unwrap()
        })),
    }
}

fn klu(metis: bool) -> Candidate {
    Candidate {
        name: if metis { "klu-metis" } else { "klu-amd" }.into(),
        build: Box::new(move || -> Box<dyn LinearSolver> {
            if metis {
                Box::new(Permuted::new(
                    "klu-metis",
                    nested_dissection,
                    Box::new(KluLu::natural()),
                ))
            } else {
                Box::new(KluLu::new())
            }
        }),
        fill: Some(Box::new(move |p, v| {
            if metis {
                // The fill of KLU on P A Pᵀ: analyse the permuted matrix directly.
                let perm = nested_dissection(p).unwrap();
                let (pp, pv) = permute(p, v, &perm);
                let mut s = KluLu::natural();
                s.analyse(&pp).unwrap();
                s.factorize(&pv).unwrap();
                s.factor_nnz().unwrap()
            } else {
                let mut s = KluLu::new();
                s.analyse(p).unwrap();
                s.factorize(v).unwrap();
                s.factor_nnz().unwrap()
            }
        })),
    }
}

/// P A Pᵀ (`perm[k]`: the unknown at position k).
fn permute(p: &Pattern, v: &[f64], perm: &[usize]) -> (Pattern, Vec<f64>) {
    let n = perm.len();
    let mut inv = vec![0; n];
    for (k, &i) in perm.iter().enumerate() {
        inv[i] = k;
    }
    let (cp, ri) = (p.col_ptr(), p.row_idx());
    let (mut col_ptr, mut row_idx, mut vals) = (vec![0], Vec::new(), Vec::new());
    for &j in perm {
        let mut col: Vec<(usize, f64)> = (cp[j]..cp[j + 1]).map(|k| (inv[ri[k]], v[k])).collect();
        col.sort_by_key(|e| e.0);
        for (r, x) in col {
            row_idx.push(r);
            vals.push(x);
        }
        col_ptr.push(row_idx.len());
    }
    (Pattern::new_checked(n, n, col_ptr, None, row_idx), vals)
}

fn candidates() -> Vec<Candidate> {
    vec![
        faer_candidate("faer-colamd", FaerLu::new),
        faer_candidate("faer-amd", || FaerLu::with_ordering(ColumnOrdering::Amd)),
        faer_candidate("faer-metis", || FaerLu::with_ordering(METIS_ORDERING)),
        faer_candidate("faer-metis-ata", || {
            FaerLu::with_ordering(ColumnOrdering::External {
                name: "faer-metis-ata",
                order: nested_dissection_ata,
            })
        }),
        faer_candidate("faer-metis-simplicial", || {
            FaerLu::with_options(Par::Seq, SupernodalThreshold::FORCE_SIMPLICIAL)
                .ordered_by(METIS_ORDERING)
        }),
        umfpack(UmfpackOrdering::Amd),
        umfpack(UmfpackOrdering::Metis),
        klu(false),
        klu(true),
    ]
}

fn measure(label: &str, pattern: &Pattern, values: &[f64], cands: &[Candidate], reps: usize) {
    let n = pattern.nrows();
    let nnz = pattern.compute_nnz();
    let b: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).sin()).collect();
    let mut solvers: Vec<Box<dyn LinearSolver>> = cands.iter().map(|c| (c.build)()).collect();
    let mut analyse = vec![0.0; cands.len()];
    for (k, s) in solvers.iter_mut().enumerate() {
        let t = Instant::now();
        s.analyse(pattern).unwrap();
        analyse[k] = ms(t);
    }
    let mut fact = vec![Vec::new(); cands.len()];
    let mut solve = vec![Vec::new(); cands.len()];
    let mut x = vec![b.clone(); cands.len()];
    for rep in 0..=reps {
        for (k, s) in solvers.iter_mut().enumerate() {
            let t = Instant::now();
            s.factorize(values).unwrap();
            let tf = ms(t);
            x[k].copy_from_slice(&b);
            let t = Instant::now();
            s.solve_in_place(&mut x[k]).unwrap();
            let ts = ms(t);
            if rep > 0 {
                fact[k].push(tf);
                solve[k].push(ts);
            } else {
                // KLU analyses inside its first factorization.
                analyse[k] += tf;
            }
        }
    }
    for (k, c) in cands.iter().enumerate() {
        let fill = c
            .fill
            .as_ref()
            .map_or("-".into(), |f| f(pattern, values).to_string());
        let diff = x[k]
            .iter()
            .zip(&x[0])
            .map(|(a, c)| (a - c).abs())
            .fold(0.0f64, f64::max)
            / x[0].iter().fold(0.0f64, |a, v| a.max(v.abs()));
        println!(
            "{label}\t{n}\t{nnz}\t{}\t{}\t{:.3}\t{:.3}\t{:.4}\t{:.1e}",
            c.name,
            fill,
            analyse[k],
            median(fact[k].clone()),
            median(solve[k].clone()),
            diff
        );
    }
}

fn main() {
    let refines: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let refines = if refines.is_empty() {
        vec![0.5, 1.0, 2.0, 4.0]
    } else {
        refines
    };
    let cands = candidates();
    println!("system\tn\tnnz(A)\tsolver\tfill\tsymbolic_ms\tnumeric_ms\tsolve_ms\tdx_vs_first");
    for refine in refines {
        let reps = if refine >= 4.0 { 7 } else { 15 };
        let mut m = model(refine, false);
        let (y, yp) = state(&m);
        let pattern = m.pattern().clone();
        let mut values = vec![0.0; pattern.compute_nnz()];
        m.jacobian(State::new(T, &y, &yp), 0.1, &mut values)
            .unwrap();
        measure(&format!("r{refine}"), &pattern, &values, &cands, reps);

        // With inertia (u, v, μ_as), cj as during the fall: the full-size LUs and the
        // condensed one (velocities eliminated, faer's LU on the rest).
        let mut m = model(refine, true);
        let (y, yp) = state(&m);
        let pattern = m.pattern().clone();
        let mut values = vec![0.0; pattern.compute_nnz()];
        m.jacobian(State::new(T, &y, &yp), 100.0, &mut values)
            .unwrap();
        let blocks = m.first_order_blocks().unwrap();
        let mut inertial: Vec<Candidate> = vec![
            faer_candidate("faer-colamd", FaerLu::new),
            klu(false),
            klu(true),
            umfpack(UmfpackOrdering::Amd),
        ];
        inertial.push(Candidate {
            name: "faer-condensed".into(),
            build: Box::new(move || Box::new(CondensedLu::new(blocks.clone()))),
            fill: None,
        });
        measure(
            &format!("r{refine}-inertia"),
            &pattern,
            &values,
            &inertial,
            reps,
        );
    }
}
