//! Range and consistency checks of a [`Case`].
//!
//! Each check names the field by its dotted path (`materials.nucleus.nu`) and states the
//! rule it broke with the numbers involved. When a rule relates two fields (r_n < r_cp),
//! the one the file actually wrote is blamed, so that the message points at the user's
//! text rather than at a default.

use std::fmt;

use super::Case;
use super::sections::{
    Active, Adhesion, Contact, Geometry, Gravity, Inertia, InertiaMode, KinematicModel, Materials,
    Mesh, Output, Phases, Solver, Start, Substrate, Viscosity,
};

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

pub(crate) use crate::solver::num;

/// Collects violations. `written(path)` tells whether the file states a field, to choose
/// which side of a two-field rule to blame.
///
/// One mistake gives one message: the checker remembers the fields reported invalid (and
/// the other fields of a failed rule relating several), and skips every later check that
/// reads one of them, since its verdict would be a knock-on of the first. Checks name the
/// fields they read besides the one they blame.
struct Checker<'a> {
    out: Vec<Violation>,
    written: &'a dyn Fn(&str) -> bool,
    /// Fields reported invalid, and the fields their failed rules related them to.
    invalid: Vec<String>,
}

impl Checker<'_> {
    /// Has any of `fields` been found invalid? A section path (`substrate`) stands for
    /// every field in it.
    fn any_invalid(&self, fields: &[&str]) -> bool {
        fields.iter().any(|f| {
            self.invalid.iter().any(|bad| {
                bad == f || (bad.starts_with(f) && bad.as_bytes().get(f.len()) == Some(&b'.'))
            })
        })
    }

    /// Reports `field`, unless it or one of the other fields the rule `reads` was found
    /// invalid already.
    fn report(&mut self, field: &str, reads: &[&str], value: String, rule: Rule) {
        if self.any_invalid(&[field]) || self.any_invalid(reads) {
            return;
        }
        self.invalid.push(field.to_string());
        self.out.push(Violation {
            field: field.to_string(),
            value,
            rule,
        });
    }

    /// Reports `field` for a rule that reads no other field.
    fn push(&mut self, field: &str, value: String, rule: Rule) {
        self.report(field, &[], value, rule);
    }

    /// Requires `ok` and a finite value; `range` states the rule, which reads `reads`
    /// besides `field`.
    fn range_given(
        &mut self,
        field: &str,
        reads: &[&str],
        v: f64,
        ok: bool,
        range: impl Into<String>,
    ) {
        if !v.is_finite() {
            let range = format!("{}, and be finite", range.into());
            self.report(field, reads, num(v), Rule::Range(range));
        } else if !ok {
            self.report(field, reads, num(v), Rule::Range(range.into()));
        }
    }

    /// Requires `ok` and a finite value; `range` states the rule.
    fn range(&mut self, field: &str, v: f64, ok: bool, range: impl Into<String>) {
        self.range_given(field, &[], v, ok, range);
    }

    fn finite(&mut self, field: &str, v: f64) {
        if !v.is_finite() {
            let rule = format!("{} is finite", short(field));
            self.push(field, num(v), Rule::Range(rule));
        }
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

    /// Requires a < b for two finite fields; blames `b` only if the file writes b but not
    /// a. A failed rule makes both fields invalid for later checks.
    fn less(&mut self, a: &str, va: f64, b: &str, vb: f64) {
        if self.any_invalid(&[a, b]) {
            return;
        }
        for (field, v) in [(a, va), (b, vb)] {
            if !v.is_finite() {
                let rule = format!("{} < {}, and be finite", short(a), short(b));
                self.push(field, num(v), Rule::Range(rule));
                return;
            }
        }
        if va < vb {
            return;
        }
        let blame_b = (self.written)(b) && !(self.written)(a);
        if blame_b {
            let rule = format!("{} > {} = {}", short(b), short(a), num(va));
            self.push(b, num(vb), Rule::Range(rule));
        } else {
            let rule = format!("{} < {} = {}", short(a), short(b), num(vb));
            self.push(a, num(va), Rule::Range(rule));
        }
        self.invalid.push(a.to_string());
        self.invalid.push(b.to_string());
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

    /// Runs the checks of the lower layers (mesh generator, material law, physics
    /// validators) that read no field found invalid, and reports what they refuse on the
    /// first of the refusal's fields that the file writes (else its first).
    fn layers(&mut self, case: &Case, layers: LayerChecks) {
        for check in layers(case) {
            let reads: Vec<&str> = check.reads.iter().map(String::as_str).collect();
            if self.any_invalid(&reads) {
                continue;
            }
            let Err(refusal) = check.run() else {
                continue;
            };
            let blamed = refusal
                .fields
                .iter()
                .find(|(f, _)| (self.written)(f))
                .or(refusal.fields.first());
            if let Some((field, value)) = blamed {
                let why = format!("refused by the {}: {}", check.layer, refusal.message);
                self.report(field, &reads, value.clone(), Rule::Conflict(why));
            }
        }
    }
}

/// Is `name` usable as one path component (an output directory): not empty, no `/` or
/// `\`, not `.` or `..`, no control characters?
pub(crate) fn is_single_path_component(name: &str) -> bool {
    !name.trim().is_empty()
        && name != "."
        && name != ".."
        && !name.contains(['/', '\\'])
        && !name.chars().any(char::is_control)
}

/// Last component of a dotted path, as used in a rule.
fn short(field: &str) -> &str {
    field.rsplit('.').next().unwrap_or(field)
}

impl Case {
    /// All violations of the schema's ranges and consistency rules, blaming the written
    /// side of two-field rules according to `written`: section by section, then what the
    /// lower layers (mesh generator, material law, physics validators) would refuse when
    /// the run sets up.
    pub(crate) fn violations(
        &self,
        written: &dyn Fn(&str) -> bool,
        layers: LayerChecks,
    ) -> Vec<Violation> {
        let mut c = Checker {
            out: Vec::new(),
            written,
            invalid: Vec::new(),
        };
        let g = &self.geometry;
        c.name(self);
        c.geometry(g);
        c.mesh(&self.mesh, g);
        c.materials(&self.materials);
        c.loads(&self.viscosity, &self.gravity);
        c.substrate(&self.substrate, g);
        c.contact(&self.contact);
        c.adhesion(self.adhesion.as_ref(), &self.contact);
        c.active(&self.active, g);
        c.fibres(&self.materials, &self.active);
        c.phases(&self.phases, self.adhesion.is_some());
        c.inertia(&self.inertia);
        c.solver_and_output(&self.solver, &self.output);
        c.layers(self, layers);
        c.out
    }
}

/// The checks of each section.
impl Checker<'_> {
    /// The name is one path component (it names the output directory).
    fn name(&mut self, case: &Case) {
        if !is_single_path_component(&case.name) {
            self.push(
                "name",
                format!("{:?}", case.name),
                Rule::Conflict(
                    "the name labels the outputs and names their directory, so it must be a \
                     single path component: not empty, no `/` or `\\`, not `.` or `..`, no \
                     control characters"
                        .into(),
                ),
            );
        }
    }

    /// Geometry: 0 < r_n < r_cp < r_c.
    fn geometry(&mut self, g: &Geometry) {
        self.finite("geometry.centre_y", g.centre_y);
        self.range(
            "geometry.r_n",
            g.r_n,
            g.r_n > 0.0,
            format!("0 < r_n < r_cp = {}", num(g.r_cp)),
        );
        self.less("geometry.r_n", g.r_n, "geometry.r_cp", g.r_cp);
        self.less("geometry.r_cp", g.r_cp, "geometry.r_c", g.r_c);
    }

    /// Mesh sizes (at most the cell radius) and the band quadrature.
    fn mesh(&mut self, m: &Mesh, g: &Geometry) {
        let sizes = [
            ("mesh.h_bottom", Some(m.h_bottom)),
            ("mesh.h_nucleus", Some(m.h_nucleus)),
            ("mesh.h_surface", m.h_surface),
        ];
        for (field, h) in sizes.into_iter().filter_map(|(f, h)| Some((f, h?))) {
            let rule = format!("0 < {} <= r_c = {}", short(field), num(g.r_c));
            self.range_given(field, &["geometry.r_c"], h, h > 0.0 && h <= g.r_c, rule);
        }
        self.positive("mesh.refine", m.refine);
        self.int_range(
            "mesh.contact_quadrature_degree",
            m.contact_quadrature_degree.into(),
            2,
            Some(20),
        );
        self.int_range(
            "mesh.contact_subdivisions",
            m.contact_subdivisions.into(),
            0,
            Some(4),
        );
    }

    /// Materials: moduli, Poisson ratios, densities, Yeoh's γ and β.
    fn materials(&mut self, mat: &Materials) {
        for (domain, d) in [
            ("nucleus", &mat.nucleus),
            ("cytoplasm", &mat.cytoplasm),
            ("membrane", &mat.membrane),
        ] {
            self.positive(&format!("materials.{domain}.e"), d.e);
            self.interval(&format!("materials.{domain}.nu"), d.nu, -1.0, 0.5, true);
            self.non_negative(&format!("materials.{domain}.rho_kg_m3"), d.rho_kg_m3);
        }
        self.interval("materials.gamma", mat.gamma, 0.0, 3.0, false);
        self.interval(
            "materials.beta_fraction",
            mat.beta_fraction,
            0.0,
            1.0,
            false,
        );
    }

    /// Fibres (MODEL.md §11): their law's ranges, and a region of `active` to lie in.
    fn fibres(&mut self, mat: &Materials, act: &Active) {
        let Some(f) = &mat.fibres else { return };
        self.non_negative("materials.fibres.k1_pa", f.k1_pa);
        self.range(
            "materials.fibres.k2",
            f.k2,
            f.k2 > 0.0 && f.k2 <= 10.0,
            "0 < k2 <= 10",
        );
        self.range(
            "materials.fibres.delta",
            f.delta,
            f.delta > 0.0 && f.delta <= 0.1,
            "0 < delta <= 0.1",
        );
        if act.pac.is_none() && act.bottom.is_none() {
            self.report(
                "materials.fibres",
                &["active"],
                "Some(..)".into(),
                Rule::Conflict(
                    "the fibres lie in the active regions (along T in the PAC, along N in the \
                     bottom region), but `active` has neither: add `active.pac` or \
                     `active.bottom` (with e: 0.0 for fibres without contraction), or remove \
                     `materials.fibres`"
                        .into(),
                ),
            );
        }
    }

    /// Viscosity and gravity: signs.
    fn loads(&mut self, v: &Viscosity, gr: &Gravity) {
        self.non_negative("viscosity.lambda_f", v.lambda_f);
        self.non_negative("viscosity.mu_f", v.mu_f);
        self.non_negative("gravity.g_m_s2", gr.g_m_s2);
        self.positive("gravity.flip_duration", gr.flip_duration);
    }

    /// Contact: positive penalty and band.
    fn contact(&mut self, ct: &Contact) {
        self.positive("contact.mu_ct_n_m3", ct.mu_ct_n_m3);
        self.positive("contact.eps_ct", ct.eps_ct);
    }

    /// Substrate: below the cell; pillars mirror symmetric about x = 0, and only with the
    /// plane-strain model.
    fn substrate(&mut self, substrate: &Substrate, g: &Geometry) {
        if g.model == KinematicModel::Axisymmetric && matches!(substrate, Substrate::Pillars(_)) {
            self.report(
                "geometry.model",
                &["substrate"],
                "Axisymmetric".into(),
                Rule::Conflict(
                    "the axisymmetric model needs a Flat substrate, but the substrate is \
                     Pillars: a pillar array is not axisymmetric about the cell's vertical \
                     axis (MODEL.md §10); use PlaneStrain for pillars"
                        .into(),
                ),
            );
        }
        if g.wedge == super::WedgeChoice::Eighth
            && (g.model != KinematicModel::ThreeD || !substrate.mirrors_diagonal())
        {
            self.report(
                "geometry.wedge",
                &["geometry.model", "substrate"],
                "Eighth".into(),
                Rule::Conflict(
                    "the eighth cell 0 ≤ z ≤ x needs the ThreeD model and a substrate that \
                     the plane x = z mirrors: Flat, or Pillars on the FourPillars lattice \
                     with first_center an odd multiple of half the period; use Quarter \
                     (or Auto)"
                        .into(),
                ),
            );
        }
        match substrate {
            Substrate::Flat(f) => {
                let bottom = g.bottom_y();
                let rule = format!("y_s < centre_y - r_c = {}", num(bottom));
                self.range_given(
                    "substrate.y_s",
                    &["geometry.centre_y", "geometry.r_c"],
                    f.y_s,
                    f.y_s < bottom,
                    rule,
                );
            }
            Substrate::Pillars(p) => {
                self.positive("substrate.width", p.width);
                self.positive("substrate.spacing", p.spacing);
                self.positive("substrate.height", p.height);
                self.range("substrate.q", p.q, p.q >= 2.0, "q >= 2");
                self.positive("substrate.gap", p.gap);
                let most = 0.5 * p.height.min(p.spacing);
                self.range_given(
                    "substrate.fillet",
                    &["substrate.height", "substrate.spacing"],
                    p.fillet,
                    p.fillet.is_finite() && p.fillet >= 0.0 && p.fillet <= most,
                    format!("0 <= fillet <= min(height, spacing)/2 = {}", num(most)),
                );
                // Mirror symmetry about x = 0: pillar axes at first_center + k·period must
                // map onto each other under x → −x.
                let rule = format!(
                    "first_center = k (width + spacing)/2 = k {} for an integer k, so that the \
                     pillars are mirror symmetric about the symmetry line x = 0",
                    num(0.5 * p.period())
                );
                self.range_given(
                    "substrate.first_center",
                    &["substrate.width", "substrate.spacing"],
                    p.first_center,
                    p.half_periods().is_some(),
                    rule,
                );
                if let Some(y_top) = p.y_top {
                    self.finite("substrate.y_top", y_top);
                }
                // The pillars must start below the cell: needs a well-formed pillar array
                // and cell, so it reads both sections.
                let reads = ["substrate", "geometry"];
                if !self.any_invalid(&reads) {
                    let y_top = p.resolved_y_top(g);
                    let gap = p.smallest_gap(g, y_top);
                    if gap.is_nan() || gap <= 0.0 {
                        let (field, value) = match p.y_top {
                            Some(y) => ("substrate.y_top", y),
                            None => ("substrate.gap", p.gap),
                        };
                        self.report(
                            field,
                            &reads,
                            num(value),
                            Rule::Conflict(format!(
                                "the pillars must start below the cell, but the smallest \
                                 initial gap is {gap:.3} µm (needs > 0)"
                            )),
                        );
                    }
                }
            }
        }
    }

    /// Adhesion: positive coefficients; a layer excluding the substrate wider than both
    /// bands.
    fn adhesion(&mut self, adhesion: Option<&Adhesion>, contact: &Contact) {
        if let Some(a) = adhesion {
            self.positive("adhesion.e_f", a.e_f);
            self.positive("adhesion.eps", a.eps);
            self.positive("adhesion.mu_as0_n_m3s", a.mu_as0_n_m3s);
            self.positive("adhesion.mu_as_max_n_m3", a.mu_as_max_n_m3);
            let reads = ["adhesion.eps", "contact.eps_ct"];
            if a.layer_excludes_substrate && !self.any_invalid(&reads) {
                let min = a.eps + contact.eps_ct;
                // Blame e_f if the file writes it, else the switch that brought the rule.
                let (field, value) = if (self.written)("adhesion.e_f")
                    || !(self.written)("adhesion.layer_excludes_substrate")
                {
                    ("adhesion.e_f", num(a.e_f))
                } else {
                    ("adhesion.layer_excludes_substrate", "true".to_string())
                };
                if !(a.e_f >= min) {
                    let e_f = if field == "adhesion.e_f" {
                        String::new()
                    } else {
                        format!(" (e_f = {})", num(a.e_f))
                    };
                    self.report(
                        field,
                        &reads,
                        value,
                        Rule::Conflict(format!(
                            "a layer that excludes the substrate (layer_excludes_substrate) \
                             needs e_f >= eps + contact.eps_ct = {}{e_f}, so that its \
                             indicator H(d + e_f) - H(d) stays in [0, 1]",
                            num(min),
                        )),
                    );
                }
            }
        }
    }

    /// Active regions: amplitudes, angles, nested ellipses inside the cell.
    fn active(&mut self, act: &Active, g: &Geometry) {
        self.positive("active.eps_a", act.eps_a);
        if let Some(pac) = &act.pac {
            self.interval("active.pac.e", pac.e, 0.0, 1.0, false);
            self.interval("active.pac.theta_deg", pac.theta_deg, -90.0, 90.0, true);
            let (inner, outer) = (pac.inner_semi_axes, pac.outer_semi_axes);
            let (inner_path, outer_path) =
                ("active.pac.inner_semi_axes", "active.pac.outer_semi_axes");
            let finite_positive =
                |(a, b): (f64, f64)| a.is_finite() && b.is_finite() && a > 0.0 && b > 0.0;
            if !finite_positive(inner) {
                self.push(
                    inner_path,
                    axes(inner),
                    Rule::Range("both inner semi-axes > 0".into()),
                );
            } else if !(outer.0.is_finite() && outer.1.is_finite()) {
                self.push(
                    outer_path,
                    axes(outer),
                    Rule::Range("both outer semi-axes finite".into()),
                );
            } else if !(inner.0 < outer.0 && inner.1 < outer.1) {
                // Blame the outer ellipse only if the file writes it and not the inner one.
                let blame_outer = (self.written)(outer_path) && !(self.written)(inner_path);
                let (field, value, rule) = if blame_outer {
                    let rule = format!("outer > inner = {}, each axis", axes(inner));
                    (outer_path, axes(outer), rule)
                } else {
                    let rule = format!("inner < outer = {}, each axis", axes(outer));
                    (inner_path, axes(inner), rule)
                };
                self.push(field, value, Rule::Range(rule));
                self.invalid
                    .extend([inner_path.to_string(), outer_path.to_string()]);
            } else if !(pac.clip_to_cell || (outer.0 < g.r_c && outer.1 < g.r_c)) {
                self.report(
                    outer_path,
                    &["geometry.r_c"],
                    axes(outer),
                    Rule::Range(format!(
                        "outer < r_c = {}, each axis (these are semi-axes, not full axes; \
                         clip_to_cell: true lets the ellipses leave the cell)",
                        num(g.r_c)
                    )),
                );
            } else if pac.clip_to_cell && !(inner.0.min(inner.1) < g.r_cp) {
                self.report(
                    inner_path,
                    &["geometry.r_cp"],
                    axes(inner),
                    Rule::Conflict(format!(
                        "with clip_to_cell the inner ellipse must leave part of the \
                         cytoplasm outside it (smaller inner semi-axis < r_cp = {}), \
                         otherwise the PAC is empty",
                        num(g.r_cp)
                    )),
                );
            }
        }
        if let Some(bottom) = &act.bottom {
            self.interval("active.bottom.e", bottom.e, 0.0, 1.0, false);
            self.interval(
                "active.bottom.theta_deg",
                bottom.theta_deg,
                -90.0,
                90.0,
                true,
            );
        }
    }

    /// Phases: 0 < T_g0 < T_as0 < T_a0, t_end > 0; the phase starts (MODEL.md §11): a time
    /// ≥ 0 or a condition's positive threshold, `Settled` for adhesion (with adhesion
    /// modelled) and `SpreadingSlows` for the active strain only.
    fn phases(&mut self, ph: &Phases, adhesion: bool) {
        self.positive("phases.t_g0", ph.t_g0);
        self.less("phases.t_g0", ph.t_g0, "phases.t_as0", ph.t_as0);
        self.less("phases.t_as0", ph.t_as0, "phases.t_a0", ph.t_a0);
        self.positive("phases.t_end", ph.t_end);
        for (field, start, adhesion_phase) in [
            ("phases.adhesion_start", ph.adhesion_start, true),
            ("phases.active_start", ph.active_start, false),
        ] {
            let Some(start) = start else { continue };
            let (name, v) = match start {
                Start::At(t) => {
                    self.range(field, t, t >= 0.0, "At(t) with t >= 0");
                    continue;
                }
                Start::Settled(v) => ("Settled", v),
                Start::SpreadingSlows(v) => ("SpreadingSlows", v),
            };
            let shown = format!("{start:?}");
            if (name == "Settled") != adhesion_phase {
                let rule = format!(
                    "{name} cannot start this phase: adhesion starts At(t) or Settled(speed), \
                     the active strain At(t) or SpreadingSlows(rate) (MODEL.md §11)"
                );
                self.push(field, shown, Rule::Conflict(rule));
            } else if adhesion_phase && !adhesion {
                let rule = "Settled starts the adhesion phase, and this case has no adhesion \
                            section"
                    .to_string();
                self.report(field, &["adhesion"], shown, Rule::Conflict(rule));
            } else {
                self.range(field, v, v > 0.0, format!("{name}(v) with v > 0"));
            }
        }
    }

    /// Inertia: drag, and a mode the cell can be integrated with.
    fn inertia(&mut self, inertia: &Inertia) {
        self.non_negative("inertia.drag", inertia.drag);
        match inertia.mode {
            InertiaMode::On => {}
            InertiaMode::Off => {
                if inertia.drag == 0.0 {
                    self.report(
                        "inertia.mode",
                        &["inertia.drag"],
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
                self.range("inertia.mode", t, t > 0.0, "OffAfter(t) with t > 0");
            }
        }
    }

    /// The solver section, by its own range check ([`crate::solver::Settings::validate`]);
    /// the output times.
    fn solver_and_output(&mut self, s: &Solver, output: &Output) {
        for bad in s.validate().err().unwrap_or_default() {
            let field = format!("solver.{}", bad.field);
            self.push(&field, bad.value, Rule::Range(bad.range));
        }
        self.int_range(
            "output.n_times",
            output.n_times.into(),
            Output::MIN_TIMES.into(),
            Some(Output::MAX_TIMES.into()),
        );
    }
}

/// Formats a pair of semi-axes for a message.
pub(crate) fn axes((a, b): (f64, f64)) -> String {
    format!("({}, {})", num(a), num(b))
}

/// A parameter that a lower layer (the mesh generator, a material law, a physics
/// validator) refuses, traced back to the case fields it comes from.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    /// The case fields (dotted paths) the refused parameter comes from, with their values
    /// as the case writes them (case units, formatted), the most likely culprit first. At
    /// least one.
    pub fields: Vec<(String, String)>,
    /// The lower layer's own message: its name for the parameter, the value in its units
    /// and the rule.
    pub message: String,
}

/// One check of a lower layer run on a case: [`crate::scene::model_params`] runs the
/// physics ones before building, and [`Case::load`] runs them all
/// ([`crate::scene::terms::layer_checks`]) so that a case it accepts is one the run
/// accepts.
pub struct LayerCheck<'c> {
    /// The layer, as a message names it ("mesh generator", "material law", ...).
    pub layer: &'static str,
    /// The case fields the check reads: dotted paths, where a section (`substrate`)
    /// stands for every field in it.
    pub reads: Vec<String>,
    check: Box<dyn Fn() -> Result<(), Refusal> + 'c>,
}

impl LayerCheck<'_> {
    /// Runs the check.
    pub fn run(&self) -> Result<(), Refusal> {
        (self.check)()
    }
}

impl std::fmt::Debug for LayerCheck<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LayerCheck")
            .field("layer", &self.layer)
            .field("reads", &self.reads)
            .finish_non_exhaustive()
    }
}

/// The checks of the lower layers that validating a case runs: the mesh generator's, the
/// material laws', the physics validators' (`crate::scene::terms::layer_checks`, which
/// translates the case into their terms one layer up).
pub type LayerChecks = for<'c> fn(&'c Case) -> Vec<LayerCheck<'c>>;

/// A [`LayerCheck`] of `layer` reading the case fields `reads`.
pub fn layer_check<'c>(
    layer: &'static str,
    reads: &[&str],
    check: impl Fn() -> Result<(), Refusal> + 'c,
) -> LayerCheck<'c> {
    LayerCheck {
        layer,
        reads: reads.iter().map(|r| r.to_string()).collect(),
        check: Box::new(check),
    }
}
