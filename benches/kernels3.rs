//! Per-call cost of the 3-D material laws and loads (`src/physics/three_d.rs`,
//! `substrate.rs`, `loads.rs`) beside their 2-D counterparts, on fixed pseudo-random inputs
//! (F within ±0.4 of I, half of them with an active strain, Ḟ within ±1):
//!
//! - `piola_total` (2-D) and `piola_total_full` in `f64`, the residual's stress;
//! - `material_point` (2-D, one `DualSVec64<4>` pass), `material_point_full` (closed form)
//!   and `dual_material_point` over `piola_total_full` (one `DualSVec64<9>` pass,
//!   instantiated here), the tangent's;
//! - `contact_force` in 2-D and in 3-D with `DualSVec64<3>` (x and J), on the
//!   default pillars, points in the contact band.
//!
//! Each benchmark runs the kernel over all `N` inputs; the machine is shared, so compare
//! ratios. `cargo bench --features bench --bench kernels3`

#![allow(non_snake_case)]

use std::hint::black_box;
use std::time::Duration;

use cellsim::physics::{
    Contact, Lattice, LatticeSubstrate, MaterialPointFull, Pillars, Substrate, Viscosity, Yeoh,
    contact_force, dual_material_point, material_point, material_point_full, piola_total,
    piola_total_full,
};
use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use num_dual::DualSVec64;

/// Inputs per benchmark iteration.
const N: usize = 256;

/// A small deterministic generator (no dependency): uniform in [a, b).
struct Lcg(u64);
impl Lcg {
    fn uniform(&mut self, a: f64, b: f64) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        a + (b - a) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// `I − a T⊗T − b N⊗N` with orthonormal N, T (the model's active strain), in 3-D.
fn active3(r: &mut Lcg) -> Matrix3<f64> {
    let axis = Vector3::new(
        r.uniform(-1.0, 1.0),
        r.uniform(-1.0, 1.0),
        r.uniform(-1.0, 1.0),
    );
    let R = nalgebra::Rotation3::from_scaled_axis(axis).into_inner();
    let (n, t) = (R.column(0).into_owned(), R.column(1).into_owned());
    Matrix3::identity() - t * t.transpose() * 0.5 - n * n.transpose() * 0.3
}

fn active2(r: &mut Lcg) -> Matrix2<f64> {
    let phi = r.uniform(-3.0, 3.0);
    let n = Vector2::new(phi.cos(), phi.sin());
    let t = Vector2::new(-n.y, n.x);
    Matrix2::identity() - t * t.transpose() * 0.5 - n * n.transpose() * 0.3
}

type In2 = (Matrix2<f64>, Matrix2<f64>, Matrix2<f64>);
type In3 = (Matrix3<f64>, Matrix3<f64>, Matrix3<f64>);

fn inputs() -> (Vec<In2>, Vec<In3>) {
    let mut r = Lcg(12345);
    let mut two = Vec::with_capacity(N);
    let mut three = Vec::with_capacity(N);
    while three.len() < N {
        let F = Matrix3::identity() + Matrix3::from_fn(|_, _| r.uniform(-0.4, 0.4));
        if F.determinant() < 0.3 {
            continue;
        }
        let G = Matrix3::from_fn(|_, _| r.uniform(-1.0, 1.0));
        let on = three.len() % 2 == 1;
        let Fa = if on {
            active3(&mut r)
        } else {
            Matrix3::identity()
        };
        three.push((F, G, Fa));
        let F2 = F.fixed_view::<2, 2>(0, 0).into_owned();
        let F2 = if F2.determinant() > 0.3 {
            F2
        } else {
            Matrix2::identity()
        };
        let Fa2 = if on {
            active2(&mut r)
        } else {
            Matrix2::identity()
        };
        two.push((F2, G.fixed_view::<2, 2>(0, 0).into_owned(), Fa2));
    }
    (two, three)
}

fn laws(c: &mut Criterion) {
    let mat = Yeoh::from_engineering(100.0, 0.485, 0.1, 0.2).unwrap();
    let visc = Viscosity {
        lambda_f: 1000.0,
        mu_f: 2e-3,
    };
    let (two, three) = inputs();
    let mut g = c.benchmark_group("laws");
    g.bench_function("piola_total-2d-f64", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (F, G, Fa) in &two {
                acc += piola_total(&mat, &visc, black_box(F), black_box(G), Fa)[(0, 0)];
            }
            acc
        })
    });
    g.bench_function("piola_total_full-f64", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (F, G, Fa) in &three {
                acc += piola_total_full(&mat, &visc, black_box(F), black_box(G), Fa)[(0, 0)];
            }
            acc
        })
    });
    g.bench_function("material_point-2d", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (F, G, Fa) in &two {
                let m = material_point(&mat, &visc, black_box(F), black_box(G), Fa);
                acc += m.dP_dF[(0, 0)] + m.dP_dFdot[(3, 3)];
            }
            acc
        })
    });
    g.bench_function("material_point_full-closed-form", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (F, G, Fa) in &three {
                let m = material_point_full(&mat, &visc, black_box(F), black_box(G), Fa);
                acc += m.dP_dF[(0, 0)] + m.dP_dFdot[(8, 8)];
            }
            acc
        })
    });
    g.bench_function("material_point_full-dual9", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (F, G, Fa) in &three {
                let (F, G) = (black_box(F), black_box(G));
                let piola = |Fd: &_, Gd: &_| piola_total_full(&mat, &visc, Fd, Gd, Fa);
                let m: MaterialPointFull =
                    dual_material_point(F, G, piola, |E| visc.piola_viscous_full(F, E));
                acc += m.dP_dF[(0, 0)] + m.dP_dFdot[(8, 8)];
            }
            acc
        })
    });
    g.finish();
}

/// The default pillars (MODEL.md §5; y_top as placed for the default cell).
fn pillars() -> Pillars {
    Pillars {
        width: 8.0,
        spacing: 8.0,
        height: 8.0,
        first_center: 8.0,
        q: 4.0,
        y_top: -0.3,
        foot: Default::default(),
        fillet: 0.0,
    }
}

fn contact(c: &mut Criterion) {
    type D3 = DualSVec64<3>;
    let law = Contact {
        mu_ct: 2e3,
        eps: 0.1,
        stiffening: 0.0,
        self_contact: false,
    };
    let p = pillars();
    let s2 = Substrate::Pillars(p);
    let s3 = LatticeSubstrate {
        plane: s2,
        lattice: Lattice::FourPillars,
    };
    // Points within 0.1 µm of a pillar's surface (tops, rounded edges, sides) or of the
    // floor: along the outward normal from surface points.
    let mut r = Lcg(777);
    let mut pts2 = Vec::with_capacity(N);
    let mut pts3 = Vec::with_capacity(N);
    for _ in 0..N {
        let (t, f) = (r.uniform(-0.4, 1.5), r.uniform(0.0, std::f64::consts::TAU));
        let cs = |v: f64| v.signum() * v.abs().powf(0.5);
        let off = r.uniform(-0.1, 0.1);
        let (u, v, w) = (cs(t.cos() * f.cos()), cs(t.sin()), cs(t.cos() * f.sin()));
        let X = Vector3::new(8.0 + 4.0 * u, p.y_top - 4.0 + 4.0 * v, 8.0 + 4.0 * w);
        let (_, n) = s3.eval(&X);
        pts3.push(X + n * off);
        let X2 = Vector2::new(8.0 + 4.0 * cs(t.cos()), p.y_top - 4.0 + 4.0 * v);
        let (_, n2) = s2.eval(&X2);
        pts2.push(X2 + n2 * off);
    }
    let mut g = c.benchmark_group("contact");
    g.bench_function("contact_force-2d-dual3", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for x in &pts2 {
                let xd = Vector2::new(
                    D3::from_re(x.x).derivative(0),
                    D3::from_re(x.y).derivative(1),
                );
                let f = contact_force(
                    &law,
                    s2.eval(black_box(&xd)),
                    D3::from_re(1.1).derivative(2),
                );
                acc += f.y.re;
            }
            acc
        })
    });
    g.bench_function("contact_force3-dual3", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for x in &pts3 {
                let xd = Vector3::from_fn(|k, _| D3::from_re(x[k]).derivative(k));
                let f = contact_force(&law, s3.eval(black_box(&xd)), D3::from_re(1.1));
                acc += f.y.re;
            }
            acc
        })
    });
    g.bench_function("contact_force3-f64", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for x in &pts3 {
                acc += contact_force(&law, s3.eval(black_box(x)), 1.1).y;
            }
            acc
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    targets = laws, contact
}
criterion_main!(benches);
