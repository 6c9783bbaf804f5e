//! `prism farm slurm` on a real Slurm: a single-node cluster brought up
//! here without systemd (munged, slurmctld and slurmd as child processes,
//! `proctrack/linuxproc`, `task/none`, state, spool, logs and the munge
//! key in a temporary directory), stopped by PID when the test ends. It
//! renders the seed scene as 4 tiles and compares the merge with a
//! one-machine render pixel for pixel, renders a 3-frame turntable, and
//! runs a job with one failing task.
//!
//! Under CI a Slurm that cannot start fails the test; elsewhere the test
//! skips and says why (`.ci/install-deps.sh` installs slurm-wlm and munge).

mod common;
use common::*;
use std::fs;
use std::net::TcpListener;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The daemons of a one-node cluster, killed (by PID) on drop.
struct Cluster {
    dir: tempfile::TempDir,
    conf: PathBuf,
    daemons: Vec<(&'static str, Child)>,
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // SIGTERM first (slurmctld then stops its slurmscriptd), SIGKILL after 5 s.
        for (_, child) in self.daemons.iter_mut().rev() {
            let _ = Command::new("kill").args(["-TERM", &child.id().to_string()]).status();
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(5) && matches!(child.try_wait(), Ok(None)) {
                std::thread::sleep(Duration::from_millis(100));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// `name` on the PATH or in the sbin directories (not on a user's PATH).
fn tool(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .chain(["/usr/sbin", "/usr/local/sbin", "/sbin"].map(PathBuf::from))
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

fn free_port() -> Result<u16, String> {
    let l = TcpListener::bind("127.0.0.1:0").map_err(|e| format!("no free port: {e}"))?;
    Ok(l.local_addr().map_err(|e| e.to_string())?.port())
}

fn command_text(c: &mut Command) -> Result<String, String> {
    let out = c.output().map_err(|e| format!("{c:?}: {e}"))?;
    if !out.status.success() {
        return Err(format!("{c:?}: {}", text(&out.stderr)));
    }
    Ok(text(&out.stdout).trim().to_owned())
}

fn wait_for(what: &str, timeout: Duration, mut ready: impl FnMut() -> bool) -> Result<(), String> {
    let start = Instant::now();
    while start.elapsed() < timeout {
        if ready() {
            return Ok(());
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    Err(format!("{what} did not come up within {} s", timeout.as_secs()))
}

impl Cluster {
    fn start() -> Result<Self, String> {
        let mut tools = Vec::new();
        for name in ["munged", "slurmctld", "slurmd", "sbatch", "squeue", "sinfo", "scancel"] {
            tools.push(
                tool(name)
                    .ok_or_else(|| format!("`{name}` is not installed (apt-get install slurm-wlm munge)"))?,
            );
        }
        let [munged, slurmctld, slurmd, ..] = &tools[..] else { unreachable!() };
        // Short paths: the munge socket's name must fit in a sockaddr_un.
        let dir =
            tempfile::Builder::new().prefix("prism-slurm").tempdir_in("/tmp").map_err(|e| e.to_string())?;
        let d = dir.path().to_path_buf();
        for sub in ["munge", "state", "spool", "log"] {
            fs::create_dir(d.join(sub)).map_err(|e| e.to_string())?;
        }
        // munged wants its socket's directories searchable by everyone.
        for p in [d.clone(), d.join("munge")] {
            fs::set_permissions(p, fs::Permissions::from_mode(0o755)).map_err(|e| e.to_string())?;
        }
        let key = d.join("munge/munge.key");
        let mut rng = prism_testkit::rng::Rng::new(std::process::id().into());
        let bytes: Vec<u8> = (0..1024).map(|_| rng.next_u32() as u8).collect();
        fs::write(&key, bytes).map_err(|e| e.to_string())?;
        fs::set_permissions(&key, fs::Permissions::from_mode(0o600)).map_err(|e| e.to_string())?;
        let socket = d.join("munge/socket");
        let user = command_text(Command::new("id").arg("-un"))?;
        let host = command_text(Command::new("hostname").arg("-s"))?;
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        let (ctl_port, d_port) = (free_port()?, free_port()?);
        let p = |s: &str| d.join(s).display().to_string();
        let conf = format!(
            "ClusterName=prismtest\nSlurmctldHost={host}(127.0.0.1)\nSlurmUser={user}\nSlurmdUser={user}\n\
             SlurmctldPort={ctl_port}\nSlurmdPort={d_port}\nAuthType=auth/munge\nCredType=cred/munge\n\
             AuthInfo=socket={}\nStateSaveLocation={}\nSlurmdSpoolDir={}\nSlurmctldPidFile={}\nSlurmdPidFile={}\n\
             SlurmctldLogFile={}\nSlurmdLogFile={}\nProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n\
             MpiDefault=none\nReturnToService=2\nSchedulerType=sched/builtin\nSelectType=select/cons_tres\n\
             SelectTypeParameters=CR_CPU\nAccountingStorageType=accounting_storage/none\n\
             JobAcctGatherType=jobacct_gather/none\nJobCompType=jobcomp/none\nMailProg=/bin/true\n\
             NodeName={host} NodeAddr=127.0.0.1 CPUs={cpus} State=UNKNOWN\n\
             PartitionName=debug Nodes={host} Default=YES MaxTime=INFINITE State=UP\n",
            socket.display(),
            p("state"),
            p("spool"),
            p("slurmctld.pid"),
            p("slurmd.pid"),
            p("log/slurmctld.log"),
            p("log/slurmd.log"),
        );
        let conf_path = d.join("slurm.conf");
        fs::write(&conf_path, conf).map_err(|e| e.to_string())?;
        let mut cluster = Cluster { dir, conf: conf_path.clone(), daemons: Vec::new() };
        let log = |name: &str| {
            fs::File::create(d.join("log").join(name)).map(Stdio::from).map_err(|e| e.to_string())
        };
        let spawn = |c: &mut Command, out: &str| -> Result<Child, String> {
            c.stdin(Stdio::null())
                .stdout(log(out)?)
                .stderr(log(out)?)
                .spawn()
                .map_err(|e| format!("{c:?}: {e}"))
        };
        let m = spawn(
            Command::new(munged)
                .arg("-F")
                .arg(format!("--key-file={}", key.display()))
                .arg(format!("--socket={}", socket.display()))
                .arg(format!("--pid-file={}", p("munge/munged.pid")))
                .arg(format!("--seed-file={}", p("munge/seed")))
                .arg(format!("--log-file={}", p("log/munged.log"))),
            "munged.out",
        )?;
        cluster.daemons.push(("munged", m));
        wait_for("munged", Duration::from_secs(10), || socket.exists()).map_err(|e| cluster.explain(&e))?;
        let c = spawn(Command::new(slurmctld).args(["-D", "-i", "-f"]).arg(&conf_path), "slurmctld.out")?;
        cluster.daemons.push(("slurmctld", c));
        let s =
            spawn(Command::new(slurmd).args(["-D", "-f"]).arg(&conf_path).args(["-N", &host]), "slurmd.out")?;
        cluster.daemons.push(("slurmd", s));
        let conf = cluster.conf.clone();
        wait_for("the Slurm node", Duration::from_secs(40), || {
            Command::new("sinfo")
                .args(["-h", "-o", "%t"])
                .env("SLURM_CONF", &conf)
                .output()
                .is_ok_and(|o| o.status.success() && text(&o.stdout).trim() == "idle")
        })
        .map_err(|e| cluster.explain(&e))?;
        Ok(cluster)
    }

    /// `why`, with whether each daemon still runs and the ends of their logs.
    fn explain(&mut self, why: &str) -> String {
        let mut s = why.to_owned();
        for (name, child) in &mut self.daemons {
            let state = match child.try_wait() {
                Ok(Some(status)) => format!("exited with {status}"),
                _ => "running".into(),
            };
            s.push_str(&format!("\n{name}: {state}"));
        }
        for f in ["munged.out", "slurmctld.out", "slurmd.out"] {
            let log = fs::read_to_string(self.dir.path().join("log").join(f)).unwrap_or_default();
            let tail: Vec<&str> = log.lines().rev().take(8).collect();
            s.push_str(&format!("\n--- {f}:\n{}", tail.into_iter().rev().collect::<Vec<_>>().join("\n")));
        }
        s
    }

    /// `prism ARGS` in `dir` against this cluster.
    fn prism(&self, dir: &Path, args: &[&str]) -> std::process::Output {
        prism_cmd(dir).args(args).env("SLURM_CONF", &self.conf).output().expect("run prism")
    }
}

fn seed() -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/seed.toml");
    p.canonicalize().expect("seed scene").display().to_string()
}

fn rgb8(p: &Path) -> Vec<u8> {
    image::open(p).unwrap_or_else(|e| panic!("{}: {e}", p.display())).to_rgb8().into_raw()
}

/// The bits of every value of a multi-layer render file (beauty, then passes).
fn float_bits(p: &Path) -> Vec<u32> {
    let r = prism_shade::read_render_exr(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let image = r.image.pixels.iter().flat_map(|v| v.to_array());
    image.chain(r.passes.passes.iter().flat_map(|a| a.data.iter().copied())).map(f32::to_bits).collect()
}

/// Small and quick: CI has two cores.
const SMALL: [&str; 8] = ["--width", "64", "--height", "36", "--spp", "2", "--threads", "1"];

#[test]
fn tiles_frames_and_a_failing_task_on_a_single_node_slurm() {
    let cluster = match Cluster::start() {
        Ok(c) => c,
        Err(why) if !prism_testkit::in_ci() => return prism_testkit::skip(&format!("no Slurm here: {why}")),
        Err(why) => panic!("CI needs a Slurm cluster for this test: {why}"),
    };
    let work = tempfile::tempdir().unwrap();
    let w = work.path();
    let scene = seed();
    let run = |args: &[&str]| cluster.prism(w, args);

    // 4 tiles, merged, against one machine's render.
    let out = run(&[
        &["farm", "slurm", &scene, "--tiles", "4", "--aov", "depth", "-o", "farm.png", "--wait"][..],
        &SMALL,
    ]
    .concat());
    assert!(out.status.success(), "farm: {}\n{}", text(&out.stderr), text(&out.stdout));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("submitted job array") && stdout.contains("submitted merge job"), "{stdout}");
    let one = run(&[&["render", &scene, "-q", "--aov", "depth", "-o", "one.png"][..], &SMALL].concat());
    assert!(one.status.success(), "{}", text(&one.stderr));
    assert_eq!(rgb8(&w.join("farm.png")), rgb8(&w.join("one.png")), "merged tiles against one render");
    assert_eq!(float_bits(&w.join("farm.aov.exr")), float_bits(&w.join("one.aov.exr")), "depth pass");
    assert_eq!(listing(&w.join("farm.farm/tiles")).len(), 4);

    // A 3-frame turntable, named with a `%`, which Slurm's `--output`
    // would read as a pattern (`%j`, the job id) if it were not escaped.
    let out = run(&[
        &["farm", "slurm", &scene, "--frames", "3", "--orbit", "30", "-o", "turn%j.png", "--wait"][..],
        &SMALL,
    ]
    .concat());
    assert!(out.status.success(), "frames: {}", text(&out.stderr));
    let local =
        run(&[&["render", &scene, "-q", "--frames", "3", "--orbit", "30", "-o", "local.png"][..], &SMALL]
            .concat());
    assert!(local.status.success(), "{}", text(&local.stderr));
    for i in 0..3 {
        let (f, l) = (w.join(format!("turn%j.000{i}.png")), w.join(format!("local.000{i}.png")));
        assert_eq!(rgb8(&f), rgb8(&l), "frame {i}");
    }

    // A backslash in the work directory: sbatch's directive reader drops
    // an undoubled one even inside quotes, so `--chdir` would name a
    // folder that does not exist and no task would run.
    let out = run(&[
        &[
            "farm",
            "slurm",
            &scene,
            "--tiles",
            "2",
            "--work-dir",
            r"back\slash.farm",
            "-o",
            "bs.png",
            "--wait",
        ][..],
        &SMALL,
    ]
    .concat());
    assert!(out.status.success(), "backslash: {}\n{}", text(&out.stderr), text(&out.stdout));
    assert_eq!(rgb8(&w.join("bs.png")), rgb8(&w.join("farm.png")), "the same image through a backslash");
    assert_eq!(listing(&w.join(r"back\slash.farm/tiles")).len(), 2);
    assert!(!w.join("backslash.farm").exists());
    // Slurm's `--output` takes no pattern where a backslash is: both
    // tasks log to the one file named as written.
    let logs = listing(&w.join(r"back\slash.farm/logs"));
    assert!(logs.contains(&"task-%a.log".to_owned()), "{logs:?}");

    // Task 2 cannot write its tile (a directory is in the way): the merge never runs.
    fs::create_dir_all(w.join("fail.farm/tiles/tile-0002.exr/in-the-way")).unwrap();
    let out =
        run(&[&["farm", "slurm", &scene, "--tiles", "4", "-o", "fail.png", "--wait"][..], &SMALL].concat());
    assert!(!out.status.success(), "a failed task must fail --wait");
    let err = text(&out.stderr);
    assert!(err.contains("1 of 4 tasks failed: 2 (exit status 1)"), "{err}");
    assert!(err.contains("no merged output was written; merge job cancelled"), "{err}");
    assert!(!w.join("fail.png").exists());
    let log = fs::read_to_string(w.join("fail.farm/logs/task-2.log")).unwrap();
    assert!(log.contains("tile-0002.exr"), "{log}");
    let queue = Command::new("squeue")
        .args(["-h", "-o", "%i %j %T"])
        .env("SLURM_CONF", &cluster.conf)
        .output()
        .unwrap();
    assert_eq!(text(&queue.stdout).trim(), "", "the merge job is cancelled, nothing is left queued");
}
