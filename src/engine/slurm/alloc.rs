//! One Slurm allocation per partition, and job steps inside it (`srun --exact`).
//!
//! The allocation is taken once with `salloc --no-shell` (or the one groove already runs in,
//! `SLURM_JOB_ID`) and released with `scancel` at the end. A job step's exit code and stderr come
//! back from `srun` directly, so neither `sacct` nor polling is needed. When a step fails,
//! `squeue` tells a failed step (the stage failed) from an allocation that ended (cancelled,
//! preempted, out of time: a rerun resumes).

use super::config::{AllocationSpec, StepResources};
use std::collections::BTreeMap;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;

/// Why a step did not succeed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StepError {
    /// The step ran and failed: its exit code and the tail of its stderr.
    Failed {
        job: String,
        code: i32,
        stderr: String,
    },
    /// The allocation is gone (cancelled, preempted, out of time).
    AllocationEnded { job: String, detail: String },
    /// Slurm's tools failed (not installed, no controller).
    Slurm(String),
}

pub struct Allocation {
    pub job: String,
    /// Taken by groove (so released by it) rather than inherited.
    owned: bool,
}

/// Every allocation of one run, by partition (`""`: the default).
pub struct Allocations {
    spec: AllocationSpec,
    held: Mutex<BTreeMap<String, Allocation>>,
    ended: AtomicBool,
    /// Allocations taken (for the closing line and tests).
    pub taken: AtomicU64,
    /// Job steps launched.
    pub steps: AtomicU64,
}

fn tail(text: &str, lines: usize) -> String {
    let all: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    all[all.len().saturating_sub(lines)..].join("\n")
}

impl Allocations {
    pub fn new(spec: AllocationSpec) -> Allocations {
        Allocations {
            spec,
            held: Mutex::new(BTreeMap::new()),
            ended: AtomicBool::new(false),
            taken: AtomicU64::new(0),
            steps: AtomicU64::new(0),
        }
    }

    /// The job id of the allocation on `partition`, taking it on first use.
    fn job_for(&self, partition: &str) -> Result<String, StepError> {
        let mut held = self.held.lock().expect("allocations lock");
        if let Some(a) = held.get(partition) {
            return Ok(a.job.clone());
        }
        let default_partition = self.spec.partition.clone().unwrap_or_default();
        // inside an allocation already (sbatch script, salloc shell): use it for its partition
        if partition == default_partition {
            if let Ok(job) = std::env::var("SLURM_JOB_ID") {
                if !job.is_empty() && std::env::var("SLURM_STEP_ID").is_err() {
                    held.insert(
                        partition.into(),
                        Allocation {
                            job: job.clone(),
                            owned: false,
                        },
                    );
                    return Ok(job);
                }
            }
        }
        let mut cmd = Command::new("salloc");
        cmd.arg("--no-shell")
            .arg(format!("--job-name={}", self.spec.job_name))
            .arg("--nodes=1")
            .arg(format!("--ntasks={}", self.spec.cpus))
            .arg("--cpus-per-task=1");
        if !partition.is_empty() {
            cmd.arg(format!("--partition={partition}"));
        }
        if let Some(t) = &self.spec.time {
            cmd.arg(format!("--time={t}"));
        }
        if let Some(m) = &self.spec.mem {
            cmd.arg(format!("--mem={m}"));
        }
        let out = cmd
            .stdin(Stdio::null())
            .output()
            .map_err(|e| StepError::Slurm(format!("cannot run salloc ({e}); install Slurm's client tools or run with --executor local")))?;
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stderr),
            String::from_utf8_lossy(&out.stdout)
        );
        let job = text
            .lines()
            .find_map(|l| l.split("Granted job allocation ").nth(1))
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty() && out.status.success());
        let Some(job) = job else {
            return Err(StepError::Slurm(format!(
                "salloc could not take an allocation: {}",
                tail(&text, 5)
            )));
        };
        self.taken.fetch_add(1, Ordering::Relaxed);
        held.insert(
            partition.into(),
            Allocation {
                job: job.clone(),
                owned: true,
            },
        );
        Ok(job)
    }

    /// Whether the allocation still runs.
    pub fn alive(job: &str) -> bool {
        Command::new("squeue")
            .args(["-h", "-j", job, "-o", "%T"])
            .stdin(Stdio::null())
            .output()
            .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "RUNNING")
            .unwrap_or(false)
    }

    /// Run `argv` as one job step with `resources`; Ok when it exited 0.
    pub fn run_step(
        &self,
        resources: &StepResources,
        name: &str,
        argv: &[String],
    ) -> Result<(), StepError> {
        let partition = resources
            .partition
            .clone()
            .or_else(|| self.spec.partition.clone())
            .unwrap_or_default();
        let job = self.job_for(&partition)?;
        if self.ended.load(Ordering::Relaxed) {
            return Err(StepError::AllocationEnded {
                job,
                detail: String::new(),
            });
        }
        let mut cmd = Command::new("srun");
        cmd.arg(format!("--jobid={job}"))
            .arg("--exact")
            .arg("--ntasks=1")
            .arg(format!("--cpus-per-task={}", resources.cpus.unwrap_or(1)))
            .arg(format!("--job-name={name}"))
            .arg("--quiet");
        if let Some(m) = &resources.mem {
            cmd.arg(format!("--mem={m}"));
        }
        if let Some(t) = &resources.time {
            cmd.arg(format!("--time={t}"));
        }
        cmd.args(argv).stdin(Stdio::null());
        self.steps.fetch_add(1, Ordering::Relaxed);
        let out = cmd.output().map_err(|e| {
            StepError::Slurm(format!(
                "cannot run srun ({e}); install Slurm's client tools or run with --executor local"
            ))
        })?;
        if out.status.success() {
            return Ok(());
        }
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        if !Self::alive(&job) {
            self.ended.store(true, Ordering::Relaxed);
            return Err(StepError::AllocationEnded {
                job,
                detail: tail(&stderr, 3),
            });
        }
        Err(StepError::Failed {
            job,
            code: out.status.code().unwrap_or(-1),
            stderr: tail(&stderr, 12),
        })
    }

    /// Release the allocations groove took.
    pub fn release(&self) {
        let held = std::mem::take(&mut *self.held.lock().expect("allocations lock"));
        for a in held.values().filter(|a| a.owned) {
            let _ = Command::new("scancel")
                .arg(&a.job)
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status();
        }
    }
}

impl Drop for Allocations {
    fn drop(&mut self) {
        self.release();
    }
}
