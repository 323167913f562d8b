//! A render spread over a real Slurm cluster by `scripts/slurm/`: a one-node cluster (munged,
//! slurmctld, slurmd from Debian's `munge` and `slurm-wlm`, installed by `scripts/setup.sh
//! --test`) started in this test's own temporary folder on free local ports, a 4-task job array
//! and its `afterok` merge submitted by `submit.sh`, one task killed on purpose (`scancel`) so
//! that the array fails and the merge never runs, the lost task resubmitted by `resubmit.sh`, and
//! the merged image compared bit for bit with `photonmap render --passes 8` in one process. The
//! daemons are stopped however the test ends. Every wait is bounded and says what it waited for,
//! with the daemons' log tails; a missing program fails the test, saying how to install it.
//!
//! Built with Embree only (the default), so that the suite, which runs once without Embree
//! too, starts the cluster once.
#![cfg(feature = "embree")]

use photonmap::film::partial::PartialFilm;
use photonmap::film::Film;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

const PROGRAMS: [&str; 7] = ["munged", "slurmctld", "slurmd", "sbatch", "squeue", "scancel", "sinfo"];

/// Where `name` is: on PATH or in the sbin folders, where Debian puts the daemons.
fn program(name: &str) -> PathBuf {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .chain(["/usr/sbin", "/sbin", "/usr/bin"].map(PathBuf::from))
        .map(|dir| dir.join(name))
        .find(|p| p.is_file())
        .unwrap_or_else(|| {
            panic!("{name} is not installed: this test runs a one-node Slurm cluster; run `bash scripts/setup.sh --test` (Debian packages slurm-wlm and munge)")
        })
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A local TCP port nobody listens on now.
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

fn command_line(cmd: &mut Command) -> String {
    let mut s = cmd.get_program().to_string_lossy().into_owned();
    for a in cmd.get_args() {
        s.push(' ');
        s.push_str(&a.to_string_lossy());
    }
    s
}

/// The cluster: its folder, configuration and daemons, stopped when dropped.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    daemons: Vec<(&'static str, Child)>,
}

impl Cluster {
    fn start(dir: &Path) -> Cluster {
        for p in PROGRAMS {
            program(p);
        }
        let user = whoami();
        let host = text(&Command::new("hostname").arg("-s").output().unwrap().stdout).trim().to_string();
        assert!(!host.is_empty() && !user.is_empty(), "no host name ({host:?}) or user name ({user:?})");
        let munge = dir.join("munge");
        std::fs::create_dir_all(&munge).unwrap();
        set_mode(&munge, 0o711);
        let key = munge.join("munge.key");
        let mut bytes = vec![0u8; 1024];
        use std::io::Read;
        std::fs::File::open("/dev/urandom").unwrap().read_exact(&mut bytes).unwrap();
        std::fs::write(&key, &bytes).unwrap();
        set_mode(&key, 0o600);
        let socket = munge.join("munge.socket");
        let mut cluster = Cluster { dir: dir.to_owned(), conf: dir.join("slurm.conf"), daemons: Vec::new() };
        let mut munged = Command::new(program("munged"));
        munged.args(["-F", "-f"]).arg(format!("--key-file={}", key.display()));
        munged.arg(format!("--socket={}", socket.display()));
        munged.arg(format!("--pid-file={}", munge.join("munged.pid").display()));
        munged.arg(format!("--log-file={}", munge.join("munged.log").display()));
        munged.arg(format!("--seed-file={}", munge.join("munged.seed").display()));
        cluster.spawn("munged", munged);
        cluster.wait_for("munged's socket", Duration::from_secs(20), || socket.exists());

        let (ctld_port, d_port) = (free_port(), free_port());
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        let memory_mb = std::fs::read_to_string("/proc/meminfo")
            .ok()
            .and_then(|m| m.lines().find(|l| l.starts_with("MemTotal:")).map(str::to_string))
            .and_then(|l| l.split_whitespace().nth(1).and_then(|kb| kb.parse::<u64>().ok()))
            .map_or(1000, |kb| kb / 1024 * 9 / 10);
        let d = dir.display();
        let conf = format!(
            "ClusterName=pmtest\n\
             SlurmctldHost={host}(127.0.0.1)\n\
             SlurmctldPort={ctld_port}\n\
             SlurmdPort={d_port}\n\
             AuthType=auth/munge\n\
             AuthInfo=socket={socket}\n\
             CredType=cred/munge\n\
             SlurmUser={user}\n\
             SlurmdUser={user}\n\
             StateSaveLocation={d}/state\n\
             SlurmdSpoolDir={d}/spool\n\
             SlurmctldPidFile={d}/slurmctld.pid\n\
             SlurmdPidFile={d}/slurmd.pid\n\
             SlurmctldLogFile={d}/slurmctld.log\n\
             SlurmdLogFile={d}/slurmd.log\n\
             ProctrackType=proctrack/linuxproc\n\
             TaskPlugin=task/none\n\
             MpiDefault=none\n\
             SchedulerType=sched/builtin\n\
             SelectType=select/cons_tres\n\
             SelectTypeParameters=CR_CPU\n\
             ReturnToService=2\n\
             JobAcctGatherType=jobacct_gather/none\n\
             AccountingStorageType=accounting_storage/none\n\
             NodeName={host} NodeAddr=127.0.0.1 CPUs={cpus} RealMemory={memory_mb} State=UNKNOWN\n\
             PartitionName=pm Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n",
            socket = socket.display(),
        );
        for sub in ["state", "spool"] {
            std::fs::create_dir_all(dir.join(sub)).unwrap();
        }
        std::fs::write(&cluster.conf, conf).unwrap();
        for daemon in ["slurmctld", "slurmd"] {
            let mut c = Command::new(program(daemon));
            c.arg("-D").arg("-f").arg(&cluster.conf);
            cluster.spawn(daemon, c);
        }
        cluster.wait_for("the node to be idle", Duration::from_secs(60), || {
            let out = cluster.run(&mut Command::new(program("sinfo")), &["-h", "-o", "%T"]);
            out.status.success() && text(&out.stdout).trim() == "idle"
        });
        cluster
    }

    fn spawn(&mut self, name: &'static str, mut cmd: Command) {
        cmd.env("SLURM_CONF", &self.conf).stdin(Stdio::null()).stdout(Stdio::null());
        let log = std::fs::File::create(self.dir.join(format!("{name}.stderr"))).unwrap();
        cmd.stderr(log);
        let child = cmd.spawn().unwrap_or_else(|e| panic!("{}: {e}", command_line(&mut cmd)));
        self.daemons.push((name, child));
    }

    /// Runs a client command against this cluster.
    fn run(&self, cmd: &mut Command, args: &[&str]) -> Output {
        cmd.args(args).env("SLURM_CONF", &self.conf).current_dir(&self.dir).stdin(Stdio::null());
        cmd.output().unwrap_or_else(|e| panic!("{}: {e}", command_line(cmd)))
    }

    /// Waits up to `limit` for `done`, failing with the daemons' logs if it never is.
    fn wait_for(&self, what: &str, limit: Duration, mut done: impl FnMut() -> bool) {
        let start = Instant::now();
        while !done() {
            if start.elapsed() > limit {
                panic!("waited {limit:?} for {what}\n{}", self.logs());
            }
            std::thread::sleep(Duration::from_millis(200));
        }
    }

    fn jobs(&self) -> String {
        let out = self.run(&mut Command::new(program("squeue")), &["-h", "-o", "%i %T %r"]);
        text(&out.stdout) + &text(&out.stderr)
    }

    fn wait_until_no_jobs(&self, what: &str) {
        self.wait_for(what, Duration::from_secs(120), || self.jobs().trim().is_empty());
    }

    /// The tails of every log of the cluster and of the jobs.
    fn logs(&self) -> String {
        let mut files: Vec<PathBuf> = ["slurmctld.log", "slurmd.log", "munge/munged.log"]
            .iter()
            .map(|f| self.dir.join(f))
            .chain(["munged", "slurmctld", "slurmd"].map(|d| self.dir.join(format!("{d}.stderr"))))
            .collect();
        if let Ok(entries) = std::fs::read_dir(self.dir.join("job/logs")) {
            files.extend(entries.flatten().map(|e| e.path()));
        }
        let mut s = format!("queue: {}\n", self.jobs());
        for f in files {
            let body = std::fs::read_to_string(&f).unwrap_or_default();
            let lines: Vec<&str> = body.lines().collect();
            let tail = lines[lines.len().saturating_sub(15)..].join("\n");
            s += &format!("--- {}\n{tail}\n", f.display());
        }
        s
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        if !self.daemons.is_empty() {
            let _ =
                self.run(&mut Command::new(program("scancel")), &["--quiet", "--full", "--user", &whoami()]);
        }
        // Newest first: slurmd, slurmctld, then munged, which they authenticate with.
        while let Some((_, mut child)) = self.daemons.pop() {
            let _ = Command::new("kill").arg("-TERM").arg(child.id().to_string()).status();
            let start = Instant::now();
            while matches!(child.try_wait(), Ok(None)) && start.elapsed() < Duration::from_secs(10) {
                std::thread::sleep(Duration::from_millis(100));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

fn whoami() -> String {
    text(&Command::new("id").arg("-un").output().unwrap().stdout).trim().to_string()
}

fn set_mode(path: &Path, mode: u32) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode)).unwrap();
}

fn bits(path: &Path) -> Vec<u32> {
    let film = Film::read_exr(path).unwrap_or_else(|e| panic!("{e}"));
    film.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).map(f32::to_bits).collect()
}

#[test]
fn a_job_array_on_slurm_merges_to_the_one_process_image_and_a_lost_task_is_restored() {
    let started = Instant::now();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    set_mode(dir, 0o711);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("scenes/cornell/cornell.toml");
    let bin = env!("CARGO_BIN_EXE_photonmap");
    let settings =
        ["--integrator", "pppm", "--width", "32", "--height", "32", "--photons", "20000", "--spp", "2"];

    // The image one process makes.
    let single = dir.join("single.exr");
    let out = Command::new(bin)
        .arg("render")
        .arg(&scene)
        .args(settings)
        .args(["--passes", "8", "-o"])
        .arg(&single)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));

    let cluster = Cluster::start(dir);
    let cluster_up = started.elapsed();

    // The photonmap the tasks run: task 2's first attempt hangs, as on a node that is lost, until
    // it is cancelled; every other run is the real program.
    let marker = dir.join("task-2-hung");
    let wrapper = dir.join("photonmap-wrapper");
    std::fs::write(
        &wrapper,
        format!(
            "#!/bin/bash\nif [ \"${{SLURM_ARRAY_TASK_ID:-}}\" = 2 ] && [ ! -e '{m}' ]; then touch '{m}'; exec sleep 300; fi\nexec '{bin}' \"$@\"\n",
            m = marker.display()
        ),
    )
    .unwrap();
    set_mode(&wrapper, 0o755);

    let job = dir.join("job");
    let fin = dir.join("final.exr");
    let submit = cluster.run(
        Command::new("bash").arg(root.join("scripts/slurm/submit.sh")),
        &[
            "--dir",
            job.to_str().unwrap(),
            "--tasks",
            "4",
            "--passes",
            "8",
            "--photonmap",
            wrapper.to_str().unwrap(),
            scene.to_str().unwrap(),
            "-o",
            fin.to_str().unwrap(),
            "--",
        ]
        .into_iter()
        .chain(settings)
        .collect::<Vec<_>>(),
    );
    assert!(
        submit.status.success(),
        "submit.sh: {}{}\n{}",
        text(&submit.stdout),
        text(&submit.stderr),
        cluster.logs()
    );
    let array = std::fs::read_to_string(job.join("array.jobid")).unwrap().trim().to_string();

    // Task 2 hangs; it is killed, so the array fails and the merge, waiting on afterok, can never
    // run (resubmit.sh cancels it).
    cluster.wait_for("task 2 to start", Duration::from_secs(60), || marker.exists());
    let cancel = cluster.run(&mut Command::new(program("scancel")), &[&format!("{array}_2")]);
    assert!(cancel.status.success(), "scancel: {}", text(&cancel.stderr));
    let merge = std::fs::read_to_string(job.join("merge.jobid")).unwrap().trim().to_string();
    let stranded = format!("{merge} PENDING DependencyNeverSatisfied");
    cluster.wait_for("the array to end, its merge stranded", Duration::from_secs(120), || {
        cluster.jobs().trim() == stranded
    });
    let part = |i: usize| job.join(format!("parts/part-{i:05}.exr"));
    assert!(!fin.exists(), "the merge ran although task 2 was killed\n{}", cluster.logs());
    assert!(!part(2).exists(), "the killed task left a part");
    for i in [0, 1, 3] {
        assert!(part(i).exists(), "task {i} left no part\n{}", cluster.logs());
    }
    // What is there does not merge, and says what is missing.
    let lacking = Command::new(bin)
        .arg("merge")
        .args([part(0), part(1), part(3)])
        .arg("-o")
        .arg(dir.join("lacking.exr"))
        .output()
        .unwrap();
    assert_eq!(lacking.status.code(), Some(1));
    assert!(text(&lacking.stderr).contains("passes 4..6 of 8 are missing"), "{}", text(&lacking.stderr));

    // The lost task again, and a new merge.
    let resubmit = cluster
        .run(Command::new("bash").arg(root.join("scripts/slurm/resubmit.sh")), &[job.to_str().unwrap()]);
    assert!(resubmit.status.success(), "resubmit.sh: {}\n{}", text(&resubmit.stderr), cluster.logs());
    assert!(text(&resubmit.stdout).contains("(2)"), "resubmitted {}", text(&resubmit.stdout));
    cluster.wait_until_no_jobs("the resubmitted task and the merge");
    assert!(fin.exists(), "no merged image\n{}", cluster.logs());

    let (want, got) = (bits(&single), bits(&fin));
    let differing = want.iter().zip(&got).filter(|(a, b)| a != b).count();
    assert_eq!(
        (want.len(), differing),
        (got.len(), 0),
        "the merged image differs from the one-process render"
    );
    // The resubmitted task's part is the one its passes make anywhere.
    let here = dir.join("part-2-here.exr");
    let out = Command::new(bin)
        .arg("render")
        .arg(&scene)
        .args(settings)
        .args(["--passes", "8", "--pass-range", "4..6", "--threads", "1", "-o"])
        .arg(&here)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    let (remote, local) = (PartialFilm::read(&part(2)).unwrap(), PartialFilm::read(&here).unwrap());
    assert!(
        remote.sums.values == local.sums.values,
        "task 2's part differs from the same passes rendered here"
    );
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(job.join("merge-stats.json")).unwrap()).unwrap();
    assert_eq!(stats["passes"], 8, "{stats}");
    drop(cluster);
    eprintln!(
        "slurm: cluster up in {:.1} s, whole test {:.1} s",
        cluster_up.as_secs_f64(),
        started.elapsed().as_secs_f64()
    );
}
