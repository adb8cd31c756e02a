//! The laboratory loadings of [`super::loading`] as resumable state machines: each [`CompressionRun::advance`]
//! / [`BoundaryStressRun::advance`] runs one record interval (or what is left of the settling stage) and
//! returns the recorded point, so that a run loop can check for interrupts, checkpoint the state between
//! intervals, and continue bitwise exactly after a resume. [`run_compression`] and
//! [`run_boundary_stress`] are these machines run to the end.
use lbdem_kernels::dem::servo::ServoLaw;
use lbdem_kernels::Real;

use super::loading::{slope, BoundaryStressTest, CompressionResult, CompressionTest, CurvePoint};
use super::packing::Packing;
use super::world::{DemWorld, PlatenControl, SampleBox};
use serde::{Deserialize, Serialize};

fn axial_stress<T: Real>(w: &DemWorld<T>, b: &SampleBox) -> T {
    T::lit(0.5) * (w.platens[b.bottom].stress() + w.platens[b.top].stress())
}

/// A compression test in progress (see [`run_compression`] for the procedure).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CompressionRun<T> {
    /// The test.
    pub test: CompressionTest<T>,
    /// The sample box's platens.
    pub sample_box: SampleBox,
    confined: bool,
    settle_left: u64,
    h0: f64,
    lateral0: f64,
    reference: f64,
    /// Points recorded so far.
    pub curve: Vec<CurvePoint>,
    peak: f64,
    peak_at: usize,
    start_step: u64,
    /// Whether the test has ended (failure past the peak, the strain limit, or a non-finite stress).
    pub finished: bool,
}

impl<T: Real> CompressionRun<T> {
    /// Set the platens of `w` (box `b`) up for the test; nothing is stepped yet.
    pub fn new(w: &mut DemWorld<T>, b: SampleBox, test: CompressionTest<T>) -> Self {
        let width0 = w.platens[b.right].wall.point[0] - w.platens[b.left].wall.point[0];
        let confined = test.confining_stress > T::zero();
        if confined {
            let servo = PlatenControl::Servo(ServoLaw {
                target_stress: test.confining_stress,
                relaxation: T::lit(0.5),
                max_speed: T::lit(10.0) * test.platen_speed,
            });
            w.platens[b.left].control = servo;
            w.platens[b.right].control = servo;
        } else {
            w.platens[b.left].active = false;
            w.platens[b.right].active = false;
            w.sample_box = None;
            w.platens[b.bottom].length = width0;
            w.platens[b.top].length = width0;
        }
        w.platens[b.bottom].control = PlatenControl::Speed(T::zero());
        w.platens[b.top].control = PlatenControl::Speed(T::zero());
        let mut run = CompressionRun {
            test,
            sample_box: b,
            confined,
            settle_left: test.settle_steps,
            h0: 0.0,
            lateral0: 0.0,
            reference: 0.0,
            curve: Vec::new(),
            peak: f64::NEG_INFINITY,
            peak_at: 0,
            start_step: 0,
            finished: false,
        };
        if run.settle_left == 0 {
            run.begin_loading(w);
        }
        run
    }

    fn lateral(&self, w: &DemWorld<T>) -> f64 {
        let b = &self.sample_box;
        if self.confined {
            (w.platens[b.right].wall.point[0] - w.platens[b.left].wall.point[0]).to_f64_exact()
        } else {
            let (lo, hi) = w.bounds();
            (hi[0] - lo[0]).to_f64_exact()
        }
    }

    fn begin_loading(&mut self, w: &mut DemWorld<T>) {
        let b = self.sample_box;
        self.h0 =
            (w.platens[b.top].wall.point[1] - w.platens[b.bottom].wall.point[1]).to_f64_exact();
        self.lateral0 = self.lateral(w);
        let start_stress = axial_stress(w, &b).to_f64_exact();
        self.reference = if self.confined {
            self.test.confining_stress.to_f64_exact()
        } else {
            start_stress
        };
        w.platens[b.bottom].control = PlatenControl::Speed(self.test.platen_speed);
        w.platens[b.top].control = PlatenControl::Speed(self.test.platen_speed);
        self.start_step = w.step_count();
    }

    /// Steps still to settle before loading starts.
    pub fn settle_left(&self) -> u64 {
        self.settle_left
    }

    /// Run the rest of the settling stage, at most one record interval of it (returns `None`), or one record
    /// interval of loading (returns the recorded point). Does nothing once finished.
    pub fn advance(&mut self, w: &mut DemWorld<T>) -> Option<CurvePoint> {
        if self.finished {
            return None;
        }
        let interval = self.test.record_interval.max(1);
        if self.settle_left > 0 {
            let n = interval.min(self.settle_left);
            for _ in 0..n {
                w.step();
            }
            self.settle_left -= n;
            if self.settle_left == 0 {
                self.begin_loading(w);
            }
            return None;
        }
        let b = self.sample_box;
        for _ in 0..interval {
            w.step();
        }
        let h = (w.platens[b.top].wall.point[1] - w.platens[b.bottom].wall.point[1]).to_f64_exact();
        let lateral = self.lateral(w);
        let sa = axial_stress(w, &b).to_f64_exact();
        let lateral_stress = if self.confined {
            0.5 * (w.platens[b.left].stress() + w.platens[b.right].stress()).to_f64_exact()
        } else {
            0.0
        };
        let (h0, lateral0, reference) = (self.h0, self.lateral0, self.reference);
        let point = CurvePoint {
            step: w.step_count(),
            axial_strain: (h0 - h) / h0,
            lateral_strain: (lateral - lateral0) / lateral0,
            axial_stress: sa,
            deviator_stress: sa - reference,
            lateral_stress,
            broken_bonds: w.breaks.len(),
        };
        self.curve.push(point);
        if sa > self.peak {
            self.peak = sa;
            self.peak_at = self.curve.len() - 1;
        }
        // Failure: past the peak, bonds broken, and the deviator down to the given fraction of its peak.
        let q_peak = self.peak - reference;
        let past_peak = self.curve.len() - 1 > self.peak_at
            && !w.breaks.is_empty()
            && q_peak > 0.0
            && sa - reference < self.test.post_peak_fraction.to_f64_exact() * q_peak;
        if past_peak || point.axial_strain > self.test.max_strain.to_f64_exact() || !sa.is_finite()
        {
            self.finished = true;
        }
        Some(point)
    }

    /// The result so far (final once [`CompressionRun::finished`]); needs at least one recorded point.
    pub fn result(&self, w: &DemWorld<T>) -> CompressionResult {
        let peak_point = self.curve[self.peak_at];
        let q_peak = peak_point.deviator_stress;
        let elastic: Vec<(f64, f64)> = self.curve[..=self.peak_at]
            .iter()
            .filter(|p| p.deviator_stress >= 0.1 * q_peak && p.deviator_stress <= 0.5 * q_peak)
            .map(|p| (p.axial_strain, p.deviator_stress))
            .collect();
        CompressionResult {
            youngs_modulus: slope(&elastic),
            peak_stress: self.peak,
            peak_deviator: q_peak,
            peak_strain: peak_point.axial_strain,
            steps: w.step_count() - self.start_step,
            curve: self.curve.clone(),
        }
    }
}

/// A [`BoundaryStressTest`] in progress (see [`run_boundary_stress`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoundaryStressRun<T> {
    /// The test.
    pub test: BoundaryStressTest<T>,
    /// The sample box's platens.
    pub sample_box: SampleBox,
    top: Vec<usize>,
    y0: f64,
    h0: f64,
    lateral0: f64,
    done: u64,
    /// Points recorded so far.
    pub curve: Vec<CurvePoint>,
}

impl<T: Real> BoundaryStressRun<T> {
    /// Set the platens and boundary loads of `w` (box `b`) up for the test; nothing is stepped yet.
    pub fn new(w: &mut DemWorld<T>, b: SampleBox, test: BoundaryStressTest<T>) -> Self {
        w.platens[b.top].active = false;
        w.sample_box = None;
        let width = w.platens[b.right].wall.point[0] - w.platens[b.left].wall.point[0];
        let height = w.platens[b.top].wall.point[1] - w.platens[b.bottom].wall.point[1];
        w.platens[b.bottom].length = width;
        w.platens[b.bottom].control = PlatenControl::Speed(T::zero());
        for side in [b.left, b.right] {
            w.platens[side].length = height;
            w.platens[side].control = PlatenControl::Servo(ServoLaw {
                target_stress: test.lateral_stress,
                relaxation: T::lit(0.5),
                max_speed: T::lit(1e-3) * height / w.timestep(),
            });
        }
        let top = w.boundary_particles(3, test.boundary_depth);
        w.apply_boundary_stress(
            &top,
            lbdem_kernels::math::vector(T::zero(), -T::one()),
            test.axial_stress,
            width,
        );
        let mut run = BoundaryStressRun {
            test,
            sample_box: b,
            top,
            y0: 0.0,
            h0: height.to_f64_exact(),
            lateral0: width.to_f64_exact(),
            done: 0,
            curve: Vec::new(),
        };
        run.y0 = run.mean_top(w);
        run
    }

    fn mean_top(&self, w: &DemWorld<T>) -> f64 {
        self.top
            .iter()
            .map(|&i| w.particles[i].position[1].to_f64_exact())
            .sum::<f64>()
            / self.top.len().max(1) as f64
    }

    /// Whether all steps have run.
    pub fn finished(&self) -> bool {
        self.done >= self.test.steps
    }

    /// Steps of the test run so far.
    pub fn steps_done(&self) -> u64 {
        self.done
    }

    /// Run one record interval (or what is left) and return the recorded point; `None` once finished.
    pub fn advance(&mut self, w: &mut DemWorld<T>) -> Option<CurvePoint> {
        if self.finished() {
            return None;
        }
        let b = self.sample_box;
        let n = self
            .test
            .record_interval
            .max(1)
            .min(self.test.steps - self.done);
        for _ in 0..n {
            w.step();
        }
        self.done += n;
        let lateral =
            (w.platens[b.right].wall.point[0] - w.platens[b.left].wall.point[0]).to_f64_exact();
        let axial = w.platens[b.bottom].stress().to_f64_exact();
        let point = CurvePoint {
            step: w.step_count(),
            axial_strain: (self.y0 - self.mean_top(w)) / self.h0,
            lateral_strain: (lateral - self.lateral0) / self.lateral0,
            axial_stress: axial,
            deviator_stress: axial
                - 0.5 * (w.platens[b.left].stress() + w.platens[b.right].stress()).to_f64_exact(),
            lateral_stress: 0.5
                * (w.platens[b.left].stress() + w.platens[b.right].stress()).to_f64_exact(),
            broken_bonds: w.breaks.len(),
        };
        self.curve.push(point);
        Some(point)
    }
}

/// Run a compression test on a bonded packing (its world is advanced in place). `on_record` sees each
/// recorded point (progress, output).
pub fn run_compression<T: Real>(
    packing: &mut Packing<T>,
    test: &CompressionTest<T>,
    mut on_record: impl FnMut(&DemWorld<T>, &CurvePoint),
) -> CompressionResult {
    let w = &mut packing.world;
    let mut run = CompressionRun::new(w, packing.sample_box, *test);
    while !run.finished {
        if let Some(point) = run.advance(w) {
            on_record(w, &point);
        }
    }
    run.result(w)
}

/// Run [`BoundaryStressTest`] on a packing: returns the record, with the axial strain measured from the mean
/// height of the loaded particles (compression positive) and the lateral strain from the lateral platens.
pub fn run_boundary_stress<T: Real>(
    packing: &mut Packing<T>,
    test: &BoundaryStressTest<T>,
    mut on_record: impl FnMut(&DemWorld<T>, &CurvePoint),
) -> Vec<CurvePoint> {
    let w = &mut packing.world;
    let mut run = BoundaryStressRun::new(w, packing.sample_box, *test);
    while let Some(point) = run.advance(w) {
        on_record(w, &point);
    }
    run.curve
}
