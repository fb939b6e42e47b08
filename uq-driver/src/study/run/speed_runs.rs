//! The runs of its own of a `hunting_speed` quantity at one design point
//! ([`crate::qoi::hunting_speed`]), on the point's FMU instance: constant-speed runs from the
//! disturbance, bisected (`mode = "bisection"`), or one simulation continued down the hunting
//! branch stage by stage, the speed set between steps (`mode = "continuation"`).

use super::error::PointError;
use super::instances::Slot;
use super::point::{ended_by_fmu, simulate_point, Trace};
use crate::fmu::{Fmu, FmuState, Instance};
use crate::qoi::evaluate::Code;
use crate::qoi::hunting_speed::{
    bisect, continue_down, keeps_hunting, HuntingSpeed, HuntingSpeedSpec, SearchMode, Stages,
};
use crate::study::plan::inputs::isclose;
use crate::study::plan::interface::SpeedRuns;

impl SpeedRuns {
    /// The search at one design point (`values` of the random parameters) on `slot`'s
    /// instance (reset, or a fresh one, between runs, by its policy): the record's (value,
    /// code) pairs of both quantities, `name` then `name_decay`.
    pub fn evaluate(
        &self,
        h: &HuntingSpeedSpec,
        fmu: &Fmu,
        slot: &mut Slot,
        values: &[f64],
    ) -> Result<[f64; 4], PointError> {
        let wrap = |speed: f64, source: PointError| PointError::SpeedRun {
            name: h.name.clone(),
            parameter: h.speed_parameter.clone(),
            speed,
            source: Box::new(source),
        };
        let outcome = match (h.mode, h.speed_step) {
            (SearchMode::Continuation, Some(speed_step)) => {
                let mut stages = Continuation {
                    runs: self,
                    h,
                    fmu,
                    slot,
                    values,
                    t: 0.0,
                    speed: f64::NAN,
                };
                let r = continue_down(h.low, h.high, speed_step, h.tolerance, &mut stages);
                r.map_err(|(speed, e)| {
                    slot.discard();
                    wrap(speed, e)
                })?
            }
            _ => bisect(h.low, h.high, h.tolerance, |v| {
                self.hunts(h, fmu, slot, values, v).map_err(|e| wrap(v, e))
            })?,
        };
        Ok(match outcome {
            HuntingSpeed::Found { hunts, decays, .. } => {
                let ok = Code::Ok as u8 as f64;
                [hunts, ok, decays, ok]
            }
            HuntingSpeed::NeverHunts => {
                let c = Code::NeverHunts as u8 as f64;
                [f64::NAN, c, f64::NAN, c]
            }
            HuntingSpeed::AlwaysHunts => {
                let c = Code::NeverStops as u8 as f64;
                [f64::NAN, c, f64::NAN, c]
            }
        })
    }

    /// One run at `speed` from the disturbance: whether it keeps hunting.
    fn hunts(
        &self,
        h: &HuntingSpeedSpec,
        fmu: &Fmu,
        slot: &mut Slot,
        values: &[f64],
        speed: f64,
    ) -> Result<bool, PointError> {
        let trace = simulate_point(
            fmu,
            slot,
            &self.run,
            values,
            &self.times,
            &[(self.speed, speed)],
            true,
        )
        .inspect_err(|_| slot.discard())?;
        self.judge(h, slot, &self.times, trace)
    }

    /// Whether the run of `trace` (its signal at `times`) keeps hunting; a run the FMU ended
    /// early or a non-finite signal is an error (the instance is discarded).
    fn judge(
        &self,
        h: &HuntingSpeedSpec,
        slot: &mut Slot,
        times: &[f64],
        trace: Trace,
    ) -> Result<bool, PointError> {
        let nt = times.len();
        if let Some((time, _)) = trace.ended {
            slot.discard();
            return Err(PointError::EndedEarly {
                time,
                stop: times[nt - 1],
            });
        }
        let series = &trace.values[..nt];
        if let Some(k) = series.iter().position(|v| !v.is_finite()) {
            slot.discard();
            return Err(PointError::NonFinite {
                signal: h.signal.clone(),
                time: times[k],
            });
        }
        Ok(keeps_hunting(times, series, h.window, h.threshold))
    }
}

/// One simulation of a point continued stage by stage ([`continue_down`]): each stage lasts
/// the quantity's `duration`, on the communication grid of its runs shifted to the stage's
/// start. The errors carry the speed of the stage that failed.
struct Continuation<'a> {
    runs: &'a SpeedRuns,
    h: &'a HuntingSpeedSpec,
    fmu: &'a Fmu,
    slot: &'a mut Slot,
    values: &'a [f64],
    /// The simulation's time now (s).
    t: f64,
    /// The speed of the current stage, for errors.
    speed: f64,
}

impl Continuation<'_> {
    fn instance(&mut self) -> Result<&mut Instance, PointError> {
        self.slot.current().ok_or_else(|| {
            PointError::Value("the continuation's instance is gone (a bug of uq-driver)".into())
        })
    }

    /// A stage from the current state at `speed`: the speed set (a tunable parameter), then
    /// the grid's steps from the current time, the signal recorded.
    fn stage(&mut self, speed: f64) -> Result<bool, PointError> {
        let runs = self.runs;
        let grid = &runs.times;
        let (vr, signals) = (runs.speed, &runs.run.signals);
        let start = self.t;
        let times: Vec<f64> = grid.iter().map(|g| start + (g - grid[0])).collect();
        let nt = times.len();
        let mut trace = Trace {
            values: vec![0.0; signals.len * nt],
            recorded: 0,
            ended: None,
        };
        let mut buf = vec![0.0; signals.len];
        let inst = self.instance()?;
        inst.set_real(&[vr], &[speed])?;
        signals.read(inst, &mut buf)?;
        trace.values[0] = buf[0];
        let mut now = start;
        for k in 1..nt {
            let step = grid[k] - grid[k - 1];
            if let Err(e) = inst.do_step(now, step, true) {
                let end = ended_by_fmu(inst, &e, now).ok_or(e)?;
                trace.ended = Some((end, None));
                break;
            }
            now += step;
            signals.read(inst, &mut buf)?;
            trace.values[k] = buf[0];
            trace.recorded = k + 1;
        }
        self.t = now;
        debug_assert!(trace.ended.is_some() || isclose(now, times[nt - 1]));
        runs.judge(self.h, self.slot, &times, trace)
    }
}

impl Stages for Continuation<'_> {
    type Saved = (FmuState, f64);
    type Error = (f64, PointError);

    fn first(&mut self, speed: f64) -> Result<bool, Self::Error> {
        self.speed = speed;
        let runs = self.runs;
        let trace = simulate_point(
            self.fmu,
            self.slot,
            &runs.run,
            self.values,
            &runs.times,
            &[(runs.speed, speed)],
            false,
        )
        .map_err(|e| (speed, e))?;
        self.t = runs.times[runs.times.len() - 1];
        runs.judge(self.h, self.slot, &runs.times, trace)
            .map_err(|e| (speed, e))
    }

    fn next(&mut self, speed: f64) -> Result<bool, Self::Error> {
        self.speed = speed;
        self.stage(speed).map_err(|e| (speed, e))
    }

    fn save(&mut self) -> Result<Self::Saved, Self::Error> {
        let (speed, t) = (self.speed, self.t);
        let inst = self.instance().map_err(|e| (speed, e))?;
        let state = inst.get_fmu_state().map_err(|e| (speed, e.into()))?;
        Ok((state, t))
    }

    fn restore(&mut self, saved: &Self::Saved) -> Result<(), Self::Error> {
        let speed = self.speed;
        let inst = self.instance().map_err(|e| (speed, e))?;
        inst.set_fmu_state(&saved.0)
            .map_err(|e| (speed, e.into()))?;
        self.t = saved.1;
        Ok(())
    }

    fn release(&mut self, saved: Self::Saved) -> Result<(), Self::Error> {
        let speed = self.speed;
        let inst = self.instance().map_err(|e| (speed, e))?;
        inst.free_fmu_state(saved.0).map_err(|e| (speed, e.into()))
    }
}
