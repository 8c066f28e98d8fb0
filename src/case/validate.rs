//! Range and consistency checks of a [`Case`].
//!
//! Each check names the field by its dotted path (`materials.nucleus.nu`) and states the
//! rule it broke with the numbers involved. When a rule relates two fields (r_n < r_cp),
//! the one the file actually wrote is blamed, so that the message points at the user's
//! text rather than at a default.

use std::fmt;

use super::Case;
use super::sections::{InertiaMode, Substrate};

/// What rule a value broke.
#[derive(Debug, Clone, PartialEq)]
pub enum Rule {
    /// The value is outside its valid range; the string is the range, e.g.
    /// `-1 < nu < 0.5`.
    Range(String),
    /// The value is not allowed together with others; the string says why.
    Conflict(String),
}

/// A field whose value breaks a rule of the schema.
#[derive(Debug, Clone, PartialEq)]
pub struct Violation {
    /// Dotted path of the field, e.g. `materials.nucleus.nu`.
    pub field: String,
    /// The offending value, formatted.
    pub value: String,
    /// The rule it breaks.
    pub rule: Rule,
}

impl Violation {
    /// Formats the violation; `default` adds that the value was not written in the file.
    pub(crate) fn describe(&self, default: bool) -> String {
        let note = if default {
            " (the default: not written in the file)"
        } else {
            ""
        };
        match &self.rule {
            Rule::Range(range) => format!(
                "{} = {}{note} is out of range (must satisfy {range})",
                self.field, self.value
            ),
            Rule::Conflict(why) => {
                format!(
                    "{} = {}{note} is not allowed: {why}",
                    self.field, self.value
                )
            }
        }
    }
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.describe(false))
    }
}

/// Formats a number for a message: plain for ordinary magnitudes, scientific otherwise.
pub(crate) fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || (1e-4..1e7).contains(&a) || !v.is_finite() {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Collects violations. `written(path)` tells whether the file states a field, to choose
/// which side of a two-field rule to blame.
struct Checker<'a> {
    out: Vec<Violation>,
    written: &'a dyn Fn(&str) -> bool,
}

impl Checker<'_> {
    fn push(&mut self, field: &str, value: String, rule: Rule) {
        self.out.push(Violation {
            field: field.to_string(),
            value,
            rule,
        });
    }

    /// Requires `ok` and a finite value; `range` states the rule.
    fn range(&mut self, field: &str, v: f64, ok: bool, range: impl Into<String>) {
        if !v.is_finite() {
            let range = format!("{}, and be finite", range.into());
            self.push(field, num(v), Rule::Range(range));
        } else if !ok {
            self.push(field, num(v), Rule::Range(range.into()));
        }
    }

    fn finite(&mut self, field: &str, v: f64) {
        self.range(field, v, true, format!("{} is finite", short(field)));
    }

    fn positive(&mut self, field: &str, v: f64) {
        self.range(field, v, v > 0.0, format!("{} > 0", short(field)));
    }

    fn non_negative(&mut self, field: &str, v: f64) {
        self.range(field, v, v >= 0.0, format!("{} >= 0", short(field)));
    }

    /// Requires lo ≤ v < hi (or lo < v < hi when `open_lo`).
    fn interval(&mut self, field: &str, v: f64, lo: f64, hi: f64, open_lo: bool) {
        let (ok_lo, op) = if open_lo {
            (v > lo, "<")
        } else {
            (v >= lo, "<=")
        };
        let rule = format!("{} {op} {} < {}", num(lo), short(field), num(hi));
        self.range(field, v, ok_lo && v < hi, rule);
    }

    /// Requires a < b for two fields; blames `b` only if the file writes b but not a.
    fn less(&mut self, a: &str, va: f64, b: &str, vb: f64) {
        if va < vb || !va.is_finite() || !vb.is_finite() {
            return; // non-finite values are reported by their own range checks
        }
        let blame_b = (self.written)(b) && !(self.written)(a);
        if blame_b {
            let rule = format!("{} > {} = {}", short(b), short(a), num(va));
            self.push(b, num(vb), Rule::Range(rule));
        } else {
            let rule = format!("{} < {} = {}", short(a), short(b), num(vb));
            self.push(a, num(va), Rule::Range(rule));
        }
    }

    fn int_range(&mut self, field: &str, v: u64, lo: u64, hi: Option<u64>) {
        let ok = v >= lo && hi.is_none_or(|hi| v <= hi);
        if !ok {
            let rule = match hi {
                Some(hi) => format!("{lo} <= {} <= {hi}", short(field)),
                None => format!("{} >= {lo}", short(field)),
            };
            self.push(field, v.to_string(), Rule::Range(rule));
        }
    }
}

/// Last component of a dotted path, as used in a rule.
fn short(field: &str) -> &str {
    field.rsplit('.').next().unwrap_or(field)
}

impl Case {
    /// All violations of the schema's ranges and consistency rules, blaming the written
    /// side of two-field rules according to `written`.
    pub(crate) fn violations(&self, written: &dyn Fn(&str) -> bool) -> Vec<Violation> {
        let mut c = Checker {
            out: Vec::new(),
            written,
        };

        if self.name.trim().is_empty() {
            c.push(
                "name",
                format!("{:?}", self.name),
                Rule::Conflict("the name must not be empty".into()),
            );
        }

        // Geometry: 0 < r_n < r_cp < r_c.
        let g = &self.geometry;
        c.finite("geometry.centre_y", g.centre_y);
        c.range(
            "geometry.r_n",
            g.r_n,
            g.r_n > 0.0,
            format!("0 < r_n < r_cp = {}", num(g.r_cp)),
        );
        c.less("geometry.r_n", g.r_n, "geometry.r_cp", g.r_cp);
        c.less("geometry.r_cp", g.r_cp, "geometry.r_c", g.r_c);

        // Mesh.
        let m = &self.mesh;
        for (field, h) in [
            ("mesh.h_bottom", m.h_bottom),
            ("mesh.h_nucleus", m.h_nucleus),
        ] {
            let rule = format!("0 < {} <= r_c = {}", short(field), num(g.r_c));
            c.range(field, h, h > 0.0 && h <= g.r_c, rule);
        }
        c.positive("mesh.refine", m.refine);
        c.int_range(
            "mesh.contact_quadrature_degree",
            m.contact_quadrature_degree.into(),
            2,
            Some(20),
        );
        c.int_range(
            "mesh.contact_subdivisions",
            m.contact_subdivisions.into(),
            0,
            Some(4),
        );

        // Materials.
        let mat = &self.materials;
        for (domain, d) in [
            ("nucleus", &mat.nucleus),
            ("cytoplasm", &mat.cytoplasm),
            ("membrane", &mat.membrane),
        ] {
            c.positive(&format!("materials.{domain}.e"), d.e);
            c.interval(&format!("materials.{domain}.nu"), d.nu, -1.0, 0.5, true);
            c.non_negative(&format!("materials.{domain}.rho_kg_m3"), d.rho_kg_m3);
        }
        c.interval("materials.gamma", mat.gamma, 0.0, 3.0, false);
        c.interval(
            "materials.beta_fraction",
            mat.beta_fraction,
            0.0,
            1.0,
            false,
        );

        // Viscosity.
        c.non_negative("viscosity.lambda_f", self.viscosity.lambda_f);
        c.non_negative("viscosity.mu_f", self.viscosity.mu_f);

        // Gravity.
        c.non_negative("gravity.g_m_s2", self.gravity.g_m_s2);
        c.positive("gravity.flip_duration", self.gravity.flip_duration);

        // Substrate: below the cell.
        match &self.substrate {
            Substrate::Flat(f) => {
                let bottom = g.bottom_y();
                let rule = format!("y_s < centre_y - r_c = {}", num(bottom));
                c.range("substrate.y_s", f.y_s, f.y_s < bottom, rule);
            }
            Substrate::Pillars(p) => {
                let before = c.out.len();
                c.positive("substrate.width", p.width);
                c.positive("substrate.spacing", p.spacing);
                c.positive("substrate.height", p.height);
                c.range("substrate.q", p.q, p.q >= 2.0, "q >= 2");
                c.positive("substrate.gap", p.gap);
                let period = p.period();
                if period.is_finite() && period > 0.0 && p.first_center.is_finite() {
                    // Mirror symmetry about x = 0: pillar axes at first_center + k·period
                    // must map onto each other under x → −x.
                    let half = 0.5 * period;
                    let r = (p.first_center / half).round() * half - p.first_center;
                    let rule = format!(
                        "first_center = k (width + spacing)/2 = k {} for an integer k, so \
                         that the pillars are mirror symmetric about the symmetry line x = 0",
                        num(half)
                    );
                    c.range(
                        "substrate.first_center",
                        p.first_center,
                        r.abs() <= 1e-9 * period,
                        rule,
                    );
                } else {
                    c.finite("substrate.first_center", p.first_center);
                }
                // The gap is only meaningful for a well-formed pillar shape.
                let shape_ok = c.out.len() == before;
                if let Some(y_top) = p.y_top {
                    c.finite("substrate.y_top", y_top);
                    if shape_ok && y_top.is_finite() && g.r_c > 0.0 {
                        let gap = p.smallest_gap(g, y_top);
                        if gap.is_nan() || gap <= 0.0 {
                            c.push(
                                "substrate.y_top",
                                num(y_top),
                                Rule::Conflict(format!(
                                    "the pillars must start below the cell, but the \
                                     smallest initial gap is {gap:.3} µm (needs > 0)"
                                )),
                            );
                        }
                    }
                }
            }
        }

        // Contact.
        c.positive("contact.mu_ct_n_m3", self.contact.mu_ct_n_m3);
        c.positive("contact.eps_ct", self.contact.eps_ct);

        // Adhesion.
        if let Some(a) = &self.adhesion {
            c.positive("adhesion.e_f", a.e_f);
            c.positive("adhesion.eps", a.eps);
            c.positive("adhesion.mu_as0_n_m3s", a.mu_as0_n_m3s);
            c.positive("adhesion.mu_as_max_n_m3", a.mu_as_max_n_m3);
        }

        // Active strain.
        let act = &self.active;
        c.positive("active.eps_a", act.eps_a);
        if let Some(pac) = &act.pac {
            c.interval("active.pac.e", pac.e, 0.0, 1.0, false);
            c.interval("active.pac.theta_deg", pac.theta_deg, -90.0, 90.0, true);
            let (inner, outer) = (pac.inner_semi_axes, pac.outer_semi_axes);
            let inner_ok = inner.0 > 0.0 && inner.1 > 0.0;
            let rule = "both inner semi-axes > 0";
            if !(inner_ok && inner.0.is_finite() && inner.1.is_finite()) {
                c.push(
                    "active.pac.inner_semi_axes",
                    axes(inner),
                    Rule::Range(rule.into()),
                );
            } else if !(inner.0 < outer.0 && inner.1 < outer.1) {
                // Blame the outer ellipse only if the file writes it and not the inner one.
                let blame_outer = (c.written)("active.pac.outer_semi_axes")
                    && !(c.written)("active.pac.inner_semi_axes");
                let (field, value, rule) = if blame_outer {
                    let rule = format!("outer > inner = {}, each axis", axes(inner));
                    ("active.pac.outer_semi_axes", axes(outer), rule)
                } else {
                    let rule = format!("inner < outer = {}, each axis", axes(outer));
                    ("active.pac.inner_semi_axes", axes(inner), rule)
                };
                c.push(field, value, Rule::Range(rule));
            } else if !(outer.0 < g.r_c && outer.1 < g.r_c) {
                c.push(
                    "active.pac.outer_semi_axes",
                    axes(outer),
                    Rule::Range(format!(
                        "outer < r_c = {}, each axis (these are semi-axes, not full axes)",
                        num(g.r_c)
                    )),
                );
            }
        }
        if let Some(bottom) = &act.bottom {
            c.interval("active.bottom.e", bottom.e, 0.0, 1.0, false);
            c.interval(
                "active.bottom.theta_deg",
                bottom.theta_deg,
                -90.0,
                90.0,
                true,
            );
        }

        // Phases: 0 < T_g0 < T_as0 < T_a0, t_end > 0.
        let ph = &self.phases;
        c.positive("phases.t_g0", ph.t_g0);
        c.less("phases.t_g0", ph.t_g0, "phases.t_as0", ph.t_as0);
        c.less("phases.t_as0", ph.t_as0, "phases.t_a0", ph.t_a0);
        c.positive("phases.t_end", ph.t_end);

        // Inertia.
        let inertia = &self.inertia;
        c.non_negative("inertia.drag", inertia.drag);
        match inertia.mode {
            InertiaMode::On => {}
            InertiaMode::Off => {
                if inertia.drag == 0.0 {
                    c.push(
                        "inertia.mode",
                        "Off".into(),
                        Rule::Conflict(
                            "without inertia and without drag (inertia.drag = 0) the cell's \
                             vertical rigid mode has no stiffness before it touches the \
                             substrate (MODEL.md §8); set inertia.drag > 0 or use \
                             OffAfter(t) with t after the cell rests"
                                .into(),
                        ),
                    );
                }
            }
            InertiaMode::OffAfter(t) => {
                c.range("inertia.mode", t, t > 0.0, "OffAfter(t) with t > 0");
            }
        }

        // Solver.
        let s = &self.solver;
        c.range(
            "solver.rtol",
            s.rtol,
            s.rtol > 0.0 && s.rtol < 1.0,
            "0 < rtol < 1",
        );
        c.positive("solver.atol", s.atol);
        c.positive("solver.bdf2_dt", s.bdf2_dt);
        c.int_range("solver.max_order", s.max_order.into(), 1, Some(5));
        c.int_range("solver.max_steps", s.max_steps, 1, None);
        if let Some(h0) = s.initial_step {
            c.positive("solver.initial_step", h0);
        }

        // Output.
        c.int_range("output.n_times", self.output.n_times.into(), 200, None);

        c.out
    }
}

fn axes((a, b): (f64, f64)) -> String {
    format!("({}, {})", num(a), num(b))
}
