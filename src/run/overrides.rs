//! The command line's changes to a scene's `[run]`: one place, so that `run` makes the run
//! that `check` judges.

use super::{Backend, GpuStorage, Kernel, Precision, RunError};
use scene::{AnyScene, ValidScene};

/// A run's length as a scene's `[run]` states it: `steps`, else `end_time_s` (s).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Length {
    /// Run to this step.
    pub steps: Option<u64>,
    /// Run to this simulated time (s).
    pub end_time_s: Option<f64>,
}

/// What `run --precision/--backend/--gpu-storage/--kernel/--steps/--end-time` change in a
/// scene's `[run]`; `None` keeps the scene's value. `run` applies them to the scene before
/// it starts, `check` before it judges.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Overrides {
    /// The fluid's arithmetic (`[run] precision`).
    pub precision: Option<Precision>,
    /// The fluid's device (`[run] backend`).
    pub backend: Option<Backend>,
    /// The GPU's population storage (`[run] gpu_storage`).
    pub gpu_storage: Option<GpuStorage>,
    /// The CPU kernel (`[run] kernel`).
    pub kernel: Option<Kernel>,
    /// Run to this step (≥ 1); replaces the scene's `steps` and `end_time_s`.
    pub steps: Option<u64>,
    /// Run to this simulated time (s, > 0); replaces the scene's `steps` and `end_time_s`.
    pub end_time_s: Option<f64>,
}

impl Overrides {
    /// Rewrite `any`'s `[run]` as these overrides say. Postcondition: the scene describes
    /// the run to make, with exactly one of `steps` and `end_time_s` set when either
    /// override is (`steps` when both are). Returns the scene's own length when the overrides replaced it (a run
    /// cut short of it is reported, not judged: [`super::RunOptions::scene_length`]).
    /// Errors, leaving `any` unchanged, when a fluid setting is given for a grains or MPM
    /// scene (those run in f64 on the CPU).
    pub fn apply(&self, any: &mut AnyScene) -> Result<Option<Length>, RunError> {
        let fluid_only = |kind: &str, path: &std::path::Path| {
            let fluid = [
                (self.precision.is_some(), "--precision"),
                (self.backend.is_some(), "--backend"),
                (self.gpu_storage.is_some(), "--gpu-storage"),
                (self.kernel.is_some(), "--kernel"),
            ];
            let given: Vec<&str> = fluid.iter().filter(|f| f.0).map(|f| f.1).collect();
            if given.is_empty() {
                return Ok(());
            }
            let (flags, verb) = (
                given.join(" and "),
                ["applies", "apply"][given.len().min(2) - 1],
            );
            Err(RunError::Override(format!(
                "{flags} {verb} to the fluid; {} is {kind} scene (f64 on the CPU): drop {flags}",
                path.display()
            )))
        };
        let (steps, end_time_s) = match any {
            AnyScene::Fluid(s) => return Ok(self.apply_fluid(s)),
            AnyScene::Grains(g) => {
                fluid_only("a grains", &g.path)?;
                (&mut g.scene.run.steps, &mut g.scene.run.end_time_s)
            }
            AnyScene::Mpm(m) => {
                fluid_only("an MPM", &m.path)?;
                (&mut m.scene.run.steps, &mut m.scene.run.end_time_s)
            }
        };
        Ok(self.replace_length(steps, end_time_s))
    }

    /// [`Overrides::apply`] to a fluid (or coupled) scene, which takes every override.
    pub fn apply_fluid(&self, scene: &mut ValidScene) -> Option<Length> {
        let run = &mut scene.scene.run;
        run.precision = self.precision.unwrap_or(run.precision);
        run.backend = self.backend.unwrap_or(run.backend);
        run.gpu_storage = self.gpu_storage.unwrap_or(run.gpu_storage);
        run.kernel = self.kernel.unwrap_or(run.kernel);
        self.replace_length(&mut run.steps, &mut run.end_time_s)
    }

    /// Replace a `[run]`'s length (`steps`, `end_time_s`) with the overrides' (`steps`
    /// first, when both are given); the scene's own length when it was replaced.
    fn replace_length(
        &self,
        steps: &mut Option<u64>,
        end_time_s: &mut Option<f64>,
    ) -> Option<Length> {
        if self.steps.is_none() && self.end_time_s.is_none() {
            return None;
        }
        let own = Length {
            steps: *steps,
            end_time_s: *end_time_s,
        };
        *steps = self.steps;
        *end_time_s = if self.steps.is_some() {
            None
        } else {
            self.end_time_s
        };
        Some(own)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn parse(text: &str) -> AnyScene {
        scene::parse_any(text, Path::new("t.toml")).expect("a valid scene")
    }

    const FLUID: &str = include_str!("../../templates/fluid.toml");
    const GRAINS: &str = include_str!("../../templates/grains.toml");

    /// A fluid scene's `[run]`: length, precision, backend, kernel.
    fn fluid_run(any: &AnyScene) -> (Length, Precision, Backend, Kernel) {
        match any {
            AnyScene::Fluid(s) => {
                let r = &s.scene.run;
                let length = Length {
                    steps: r.steps,
                    end_time_s: r.end_time_s,
                };
                (length, r.precision, r.backend, r.kernel)
            }
            _ => panic!("a fluid scene"),
        }
    }

    #[test]
    fn the_length_is_replaced_whole_and_the_rest_field_by_field() {
        let mut any = parse(FLUID);
        let o = Overrides {
            precision: Some(Precision::F32),
            steps: Some(7),
            ..Default::default()
        };
        let own = o.apply(&mut any).expect("applies to a fluid scene");
        let template = fluid_run(&parse(FLUID));
        assert_eq!(own, Some(template.0), "the scene's own length comes back");
        let run = fluid_run(&any);
        assert_eq!(run.1, Precision::F32);
        assert_eq!(
            run.0,
            Length {
                steps: Some(7),
                end_time_s: None
            }
        );
        assert_eq!((run.2, run.3), (template.2, template.3));
        // No override leaves the scene as it was.
        let mut untouched = parse(FLUID);
        let own = Overrides::default().apply(&mut untouched);
        assert_eq!(own.expect("nothing to apply"), None);
        assert_eq!(fluid_run(&untouched), template);
    }

    #[test]
    fn a_fluid_setting_on_a_grains_scene_is_refused_by_name() {
        let mut any = parse(GRAINS);
        let o = Overrides {
            kernel: Some(Kernel::InPlace),
            ..Default::default()
        };
        let e = o.apply(&mut any).expect_err("grains have no fluid kernel");
        assert!(
            e.to_string().contains("--kernel applies to the fluid"),
            "{e}"
        );
        let o = Overrides {
            end_time_s: Some(0.1),
            ..Default::default()
        };
        let own = o.apply(&mut any).expect("a length applies to any scene");
        assert!(own.is_some());
        let AnyScene::Grains(g) = &any else {
            panic!("a grains scene")
        };
        assert_eq!(
            (g.scene.run.steps, g.scene.run.end_time_s),
            (None, Some(0.1))
        );
    }
}
