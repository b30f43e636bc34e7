//! # The emulated flight computer: the board binary in QEMU, over an emulated UART
//!
//! [`QemuBoard::start`] runs the board binary (`firmware/boards/mps2-an500`) in `qemu-system-arm` and connects to
//! its UART0 through a loopback socket:
//!
//! 1. bind `127.0.0.1:0` (the OS picks a free port);
//! 2. spawn `qemu-system-arm -machine mps2-an500 -cpu cortex-m7 -nographic -monitor none
//!    -semihosting-config enable=on,target=native -chardev socket,id=u0,host=127.0.0.1,port=PORT0,nodelay=on
//!    -serial chardev:u0 -chardev socket,id=u1,host=127.0.0.1,port=PORT1,nodelay=on -serial chardev:u1
//!    [-icount shift=0] -kernel ELF [-append BOOT_WORDS]`; QEMU connects to us as a client (`nodelay=on` avoids
//!    ~44 ms of Nagle delay per reply, measured). UART0 carries the flight protocol; UART1 is the board's
//!    test-harness control port (hello, lockstep run commands, quit; see the board's `flight.rs`);
//! 3. accept both connections (bounded by [`QemuConfig::connect_timeout`]);
//! 4. wait for the firmware's hello byte `H` on the control port (the handshake; bounded by
//!    [`QemuConfig::ready_timeout`]); the host sends nothing before it, because bytes sent before the guest enables
//!    its receiver can stall ~1 s. In free-running mode the board's boot `Telemetry` frame (the protocol's ready
//!    frame) then arrives on UART0;
//! 5. move bytes ([`QemuBoard::send`], [`QemuBoard::recv`]); [`QemuBoard::quit`] asks the board for its resource
//!    report and waits for its exit.
//!
//! [`crate::link::qemu::QemuLink`] puts this behind the simulator's link abstraction.
//!
//! QEMU is killed when the [`QemuBoard`] is dropped. The board's semihosting output (report lines
//! `board: key=value ...`, fault reports) is captured and returned by [`QemuBoard::finish`].
//!
//! The board binary is built separately (it is its own cargo workspace, cross-compiled):
//! `cargo build --release` in `firmware/boards/mps2-an500` (the directory's `.cargo/config.toml` picks the target),
//! or [`build_board_elf`]. [`board_elf_path`] finds the result; `TETHERBOT_BOARD_ELF` overrides the path.

pub mod bench;
pub mod perf;
pub mod report;

use core::time::Duration;
use std::io::{self, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Instant;

/// The emulator executable.
pub const QEMU_BINARY: &str = "qemu-system-arm";
/// How to install it (Debian / Ubuntu).
pub const QEMU_INSTALL_HINT: &str =
    "install it with `apt-get install -y --no-install-recommends qemu-system-arm` \
(Debian/Ubuntu; use sudo when not root)";
/// The board's crate directory, relative to the repository root.
pub const BOARD_DIR: &str = "firmware/boards/mps2-an500";
/// The board's target triple.
pub const BOARD_TARGET: &str = "thumbv7em-none-eabihf";
/// The board binary's name.
pub const BOARD_BIN: &str = "board-mps2-an500";
/// Polling period while waiting for QEMU to connect or exit.
const POLL: Duration = Duration::from_millis(2);

/// What can go wrong starting or talking to the emulated board. Each message says what to do.
#[derive(Debug)]
pub enum QemuError {
    /// `qemu-system-arm` is not on the PATH.
    NotInstalled,
    /// The board ELF does not exist.
    ElfMissing(PathBuf),
    /// Building the board ELF failed.
    BuildFailed(String),
    /// QEMU did not connect to the UART socket in time.
    ConnectTimeout(Duration, String),
    /// The firmware did not send its ready frame in time.
    ReadyTimeout(Duration, String),
    /// QEMU exited early (status and its output).
    Exited(Option<i32>, String),
    /// A socket or process error.
    Io(io::Error),
}

impl core::fmt::Display for QemuError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NotInstalled => write!(
                f,
                "`{QEMU_BINARY}` was not found on the PATH: {QEMU_INSTALL_HINT}"
            ),
            Self::ElfMissing(p) => write!(
                f,
                "board binary {} not found: build it with `cargo build --release` in {BOARD_DIR} \
                 (or set TETHERBOT_BOARD_ELF)",
                p.display()
            ),
            Self::BuildFailed(e) => write!(f, "building the board binary failed:\n{e}"),
            Self::ConnectTimeout(t, out) => {
                write!(
                    f,
                    "QEMU did not connect to the UART socket within {t:?}; its output:\n{out}"
                )
            }
            Self::ReadyTimeout(t, out) => {
                write!(
                    f,
                    "the board sent no ready frame within {t:?}; its output:\n{out}"
                )
            }
            Self::Exited(code, out) => write!(
                f,
                "QEMU exited early with status {code:?}; its output:\n{out}"
            ),
            Self::Io(e) => write!(f, "emulated board link: {e}"),
        }
    }
}

impl core::error::Error for QemuError {}

impl From<io::Error> for QemuError {
    fn from(e: io::Error) -> Self {
        Self::Io(e)
    }
}

/// True if `qemu-system-arm` can be run.
pub fn qemu_available() -> bool {
    Command::new(QEMU_BINARY)
        .arg("--version")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

/// The repository root (this crate's parent directory).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// Where the board ELF is: `$TETHERBOT_BOARD_ELF`, else the release build in the board directory.
pub fn board_elf_path() -> PathBuf {
    if let Some(p) = std::env::var_os("TETHERBOT_BOARD_ELF") {
        return PathBuf::from(p);
    }
    repo_root()
        .join(BOARD_DIR)
        .join("target")
        .join(BOARD_TARGET)
        .join("release")
        .join(BOARD_BIN)
}

/// Builds the board ELF (`cargo build --release --target thumbv7em-none-eabihf` in the board directory) and
/// returns its path. Incremental: a no-op build takes well under a second; a cold build about a minute on 2 cores.
pub fn build_board_elf() -> Result<PathBuf, QemuError> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(repo_root().join(BOARD_DIR))
        .args(["build", "--release", "--target", BOARD_TARGET])
        .env_remove("CARGO_TARGET_DIR")
        .env_remove("CARGO_BUILD_TARGET")
        .env_remove("RUSTFLAGS")
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .stdin(Stdio::null())
        .output()?;
    if !out.status.success() {
        return Err(QemuError::BuildFailed(
            String::from_utf8_lossy(&out.stderr).into_owned(),
        ));
    }
    let elf = repo_root()
        .join(BOARD_DIR)
        .join("target")
        .join(BOARD_TARGET)
        .join("release")
        .join(BOARD_BIN);
    if elf.is_file() {
        Ok(elf)
    } else {
        Err(QemuError::ElfMissing(elf))
    }
}

/// How to start the emulated board.
#[derive(Debug, Clone)]
pub struct QemuConfig {
    /// The board ELF.
    pub elf: PathBuf,
    /// Pass `-icount shift=0`: one instruction = 1 ns of virtual time, deterministic instruction counts
    /// (the emulation runs about 4x slower than without it).
    pub icount: bool,
    /// Boot words for the board (`-append`), e.g. `tetherbot.mode=bench`; see the board's `host.rs`.
    pub boot_words: Option<String>,
    /// Bound on QEMU connecting to the socket.
    pub connect_timeout: Duration,
    /// Bound on the ready frame after connecting.
    pub ready_timeout: Duration,
}

impl QemuConfig {
    /// Defaults for `elf`: no icount, 10 s to connect, 10 s to ready.
    pub fn new(elf: PathBuf) -> Self {
        Self {
            elf,
            icount: false,
            boot_words: None,
            connect_timeout: Duration::from_secs(10),
            ready_timeout: Duration::from_secs(10),
        }
    }

    fn command(&self, ports: Option<(u16, u16)>) -> Command {
        let mut cmd = Command::new(QEMU_BINARY);
        cmd.args([
            "-machine",
            "mps2-an500",
            "-cpu",
            "cortex-m7",
            "-nographic",
            "-monitor",
            "none",
        ]);
        cmd.args(["-semihosting-config", "enable=on,target=native"]);
        match ports {
            Some((data, control)) => {
                cmd.arg("-chardev").arg(format!(
                    "socket,id=u0,host=127.0.0.1,port={data},nodelay=on"
                ));
                cmd.args(["-serial", "chardev:u0"]);
                cmd.arg("-chardev").arg(format!(
                    "socket,id=u1,host=127.0.0.1,port={control},nodelay=on"
                ));
                cmd.args(["-serial", "chardev:u1"]);
            }
            None => {
                cmd.args(["-serial", "null"]);
            }
        }
        if self.icount {
            cmd.args(["-icount", "shift=0"]);
        }
        cmd.arg("-kernel").arg(&self.elf);
        if let Some(words) = &self.boot_words {
            cmd.arg("-append").arg(words);
        }
        cmd.stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        cmd
    }

    fn check(&self) -> Result<(), QemuError> {
        if !self.elf.is_file() {
            return Err(QemuError::ElfMissing(self.elf.clone()));
        }
        if !qemu_available() {
            return Err(QemuError::NotInstalled);
        }
        Ok(())
    }
}

/// QEMU's captured standard output (semihosting prints) and standard error (fault reports, QEMU messages).
#[derive(Debug, Clone, Default)]
pub struct Captured {
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
}

impl Captured {
    /// Both streams, for error messages.
    pub fn both(&self) -> String {
        format!("{}{}", self.stdout, self.stderr)
    }

    /// The value of `key=value` in the last `board:` or `bench:` line that has it.
    pub fn value(&self, key: &str) -> Option<String> {
        let prefix = format!("{key}=");
        self.both()
            .lines()
            .rev()
            .flat_map(|l| l.split_whitespace().rev().collect::<Vec<_>>())
            .find_map(|w| w.strip_prefix(&prefix).map(str::to_owned))
    }
}

/// How a run of the board ended.
#[derive(Debug, Clone)]
pub struct QemuExit {
    /// QEMU's exit status (semihosting exit: 0 success, 1 failure).
    pub status: ExitStatus,
    /// What it printed.
    pub output: Captured,
}

fn spawn_capture(child: &mut Child) -> (Arc<Mutex<Captured>>, Vec<JoinHandle<()>>) {
    let captured = Arc::new(Mutex::new(Captured::default()));
    let mut handles = Vec::new();
    if let Some(mut out) = child.stdout.take() {
        let c = Arc::clone(&captured);
        handles.push(std::thread::spawn(move || {
            let mut s = String::new();
            let mut buf = [0u8; 4096];
            while let Ok(n) = out.read(&mut buf) {
                if n == 0 {
                    break;
                }
                s.push_str(&String::from_utf8_lossy(&buf[..n]));
                if let Ok(mut g) = c.lock() {
                    g.stdout.clone_from(&s);
                }
            }
        }));
    }
    if let Some(mut err) = child.stderr.take() {
        let c = Arc::clone(&captured);
        handles.push(std::thread::spawn(move || {
            let mut s = String::new();
            let mut buf = [0u8; 4096];
            while let Ok(n) = err.read(&mut buf) {
                if n == 0 {
                    break;
                }
                s.push_str(&String::from_utf8_lossy(&buf[..n]));
                if let Ok(mut g) = c.lock() {
                    g.stderr.clone_from(&s);
                }
            }
        }));
    }
    (captured, handles)
}

fn snapshot(c: &Arc<Mutex<Captured>>) -> Captured {
    c.lock().map(|g| g.clone()).unwrap_or_default()
}

/// Runs the board without a UART connection until it exits (bench mode, fault probes), bounded by `timeout`.
pub fn run_to_exit(cfg: &QemuConfig, timeout: Duration) -> Result<QemuExit, QemuError> {
    cfg.check()?;
    let mut child = cfg.command(None).spawn()?;
    let (captured, handles) = spawn_capture(&mut child);
    let deadline = Instant::now() + timeout;
    loop {
        if let Some(status) = child.try_wait()? {
            for h in handles {
                let _ = h.join();
            }
            return Ok(QemuExit {
                status,
                output: snapshot(&captured),
            });
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            return Err(QemuError::Io(io::Error::new(
                io::ErrorKind::TimedOut,
                format!(
                    "the board did not exit within {timeout:?}; output:\n{}",
                    snapshot(&captured).both()
                ),
            )));
        }
        std::thread::sleep(POLL);
    }
}

/// A running emulated board, connected and past its hello.
pub struct QemuBoard {
    child: Option<Child>,
    stream: TcpStream,
    control: TcpStream,
    captured: Arc<Mutex<Captured>>,
    readers: Vec<JoinHandle<()>>,
    pending: Vec<u8>,
    control_pending: Vec<u8>,
    boot_to_ready: Duration,
}

fn accept_within(
    listener: &TcpListener,
    child: &mut Child,
    captured: &Arc<Mutex<Captured>>,
    t0: Instant,
    timeout: Duration,
) -> Result<TcpStream, QemuError> {
    loop {
        match listener.accept() {
            Ok((s, _)) => {
                s.set_nonblocking(false)?;
                s.set_nodelay(true)?;
                return Ok(s);
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => {}
            Err(e) => return Err(e.into()),
        }
        if let Some(status) = child.try_wait()? {
            std::thread::sleep(Duration::from_millis(20));
            return Err(QemuError::Exited(status.code(), snapshot(captured).both()));
        }
        if t0.elapsed() > timeout {
            let _ = child.kill();
            let _ = child.wait();
            return Err(QemuError::ConnectTimeout(
                timeout,
                snapshot(captured).both(),
            ));
        }
        std::thread::sleep(POLL);
    }
}

impl QemuBoard {
    /// Starts QEMU, accepts its two UART connections and waits for the hello byte on the control port.
    pub fn start(cfg: &QemuConfig) -> Result<Self, QemuError> {
        cfg.check()?;
        let data_listener = TcpListener::bind("127.0.0.1:0")?;
        let control_listener = TcpListener::bind("127.0.0.1:0")?;
        data_listener.set_nonblocking(true)?;
        control_listener.set_nonblocking(true)?;
        let ports = (
            data_listener.local_addr()?.port(),
            control_listener.local_addr()?.port(),
        );
        let t0 = Instant::now();
        let mut child = cfg.command(Some(ports)).spawn()?;
        let (captured, readers) = spawn_capture(&mut child);
        let stream = accept_within(
            &data_listener,
            &mut child,
            &captured,
            t0,
            cfg.connect_timeout,
        )?;
        let control = accept_within(
            &control_listener,
            &mut child,
            &captured,
            t0,
            cfg.connect_timeout,
        )?;
        let mut board = Self {
            child: Some(child),
            stream,
            control,
            captured,
            readers,
            pending: Vec::new(),
            control_pending: Vec::new(),
            boot_to_ready: Duration::ZERO,
        };
        let mut hello = [0u8; 1];
        match board.control_recv_exact(&mut hello, cfg.ready_timeout) {
            Ok(()) if hello == *b"H" => {
                board.boot_to_ready = t0.elapsed();
                Ok(board)
            }
            Ok(()) => Err(QemuError::Io(io::Error::new(
                io::ErrorKind::InvalidData,
                format!("unexpected hello byte 0x{:02x} from the board", hello[0]),
            ))),
            Err(e) if e.kind() == io::ErrorKind::TimedOut => Err(QemuError::ReadyTimeout(
                cfg.ready_timeout,
                board.output().both(),
            )),
            Err(_) => {
                let code = board
                    .wait_child(Duration::from_secs(2))
                    .and_then(|s| s.code());
                Err(QemuError::Exited(code, board.output().both()))
            }
        }
    }

    /// Resets the board with the control port's reboot command (`B`: a system reset, as a watchdog bite) and waits
    /// up to `timeout` for the rebooted firmware's hello. QEMU keeps running; RAM outside the ELF's sections (the
    /// board's `.uninit`, where the tether checkpoint lives) keeps its content.
    pub fn reboot(&mut self, timeout: Duration) -> io::Result<()> {
        self.control_send(b"B")?;
        self.await_hello(timeout)
    }

    /// Waits for the hello of a rebooted board.
    fn await_hello(&mut self, timeout: Duration) -> io::Result<()> {
        let mut hello = [0u8; 1];
        self.control_recv_exact(&mut hello, timeout)?;
        if hello != *b"H" {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                format!("unexpected hello byte 0x{:02x} from the rebooted board", hello[0]),
            ));
        }
        Ok(())
    }

    /// Makes the board's flight loop stop kicking its watchdog (control byte `W`, test builds only): the CMSDK
    /// watchdog's interrupt (the NMI) lets the bite pass and its reset output reboots the Cortex-M7, as a stuck
    /// flight loop would; waits for the rebooted board's hello.
    pub fn bite_watchdog(&mut self, timeout: Duration) -> io::Result<()> {
        self.control_send(b"W")?;
        self.await_hello(timeout)
    }

    /// Sends `bytes` on the control port.
    pub fn control_send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.control.write_all(bytes)
    }

    /// Reads exactly `buf.len()` bytes from the control port within `timeout` (`TimedOut` otherwise, keeping
    /// what arrived for the next call; `UnexpectedEof` if the board went away).
    pub fn control_recv_exact(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<()> {
        let deadline = Instant::now() + timeout;
        let mut chunk = [0u8; 64];
        while self.control_pending.len() < buf.len() {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(io::Error::new(
                    io::ErrorKind::TimedOut,
                    "control port: no reply in time",
                ));
            }
            self.control.set_read_timeout(Some(left))?;
            match self.control.read(&mut chunk) {
                Ok(0) => {
                    return Err(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "the board closed its control port",
                    ))
                }
                Ok(n) => self.control_pending.extend_from_slice(&chunk[..n]),
                Err(e)
                    if matches!(
                        e.kind(),
                        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                    ) => {}
                Err(e) => return Err(e),
            }
        }
        buf.copy_from_slice(&self.control_pending[..buf.len()]);
        self.control_pending.drain(..buf.len());
        Ok(())
    }

    /// Asks the board to print its resource report and exit (`Q` on the control port); waits at most `timeout`.
    pub fn quit(mut self, timeout: Duration) -> Result<QemuExit, QemuError> {
        self.control_send(b"Q")?;
        self.finish(timeout)
    }

    /// Host wall-clock time from spawning QEMU to the hello byte.
    pub fn boot_to_ready(&self) -> Duration {
        self.boot_to_ready
    }

    /// Sends all of `bytes` to the board's UART.
    pub fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.stream.write_all(bytes)
    }

    /// Receives up to `buf.len()` bytes, waiting at most `timeout`; `Ok(0)` on timeout. A closed connection
    /// (QEMU exited) is `Err(UnexpectedEof)`.
    pub fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        if !self.pending.is_empty() {
            let n = buf.len().min(self.pending.len());
            buf[..n].copy_from_slice(&self.pending[..n]);
            self.pending.drain(..n);
            return Ok(n);
        }
        self.stream
            .set_read_timeout(Some(timeout.max(Duration::from_micros(1))))?;
        match self.stream.read(buf) {
            Ok(0) if !buf.is_empty() => Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                "the board closed the UART",
            )),
            Ok(n) => Ok(n),
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) =>
            {
                Ok(0)
            }
            Err(e) => Err(e),
        }
    }

    /// Non-blocking receive: whatever is pending now.
    pub fn try_recv(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if !self.pending.is_empty() {
            return self.recv(buf, Duration::ZERO);
        }
        self.stream.set_nonblocking(true)?;
        let r = match self.stream.read(buf) {
            Ok(0) if !buf.is_empty() => Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                "the board closed the UART",
            )),
            Ok(n) => Ok(n),
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => Ok(0),
            Err(e) => Err(e),
        };
        self.stream.set_nonblocking(false)?;
        r
    }

    /// What QEMU printed so far.
    pub fn output(&self) -> Captured {
        snapshot(&self.captured)
    }

    fn wait_child(&mut self, timeout: Duration) -> Option<ExitStatus> {
        let child = self.child.as_mut()?;
        let deadline = Instant::now() + timeout;
        loop {
            match child.try_wait() {
                Ok(Some(s)) => return Some(s),
                Ok(None) if Instant::now() < deadline => std::thread::sleep(POLL),
                _ => return None,
            }
        }
    }

    /// Waits (bounded) for the board to exit by itself, e.g. after a shutdown request, and returns its status
    /// and output. On timeout QEMU is killed and the error says so.
    pub fn finish(mut self, timeout: Duration) -> Result<QemuExit, QemuError> {
        let status = self.wait_child(timeout);
        if let Some(mut child) = self.child.take() {
            if status.is_none() {
                let _ = child.kill();
                let _ = child.wait();
            }
        }
        for h in core::mem::take(&mut self.readers) {
            let _ = h.join();
        }
        let output = snapshot(&self.captured);
        match status {
            Some(status) => Ok(QemuExit { status, output }),
            None => Err(QemuError::Io(io::Error::new(
                io::ErrorKind::TimedOut,
                format!(
                    "the board did not exit within {timeout:?}; output:\n{}",
                    output.both()
                ),
            ))),
        }
    }
}

impl Drop for QemuBoard {
    fn drop(&mut self) {
        if let Some(mut child) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// What an on-target test does about QEMU.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AbsentQemu {
    /// QEMU is there: run.
    Run,
    /// QEMU is absent outside CI: skip, printing this note.
    Skip(String),
    /// QEMU is absent under `CI=true` (or `CI=1`): fail.
    Fail,
}

/// The policy of [`board_for_tests`], apart from the environment: `ci` is the value of `CI`.
pub fn absent_qemu_policy(qemu_available: bool, ci: Option<&str>, test: &str) -> AbsentQemu {
    if qemu_available {
        AbsentQemu::Run
    } else if matches!(ci, Some("true" | "1")) {
        AbsentQemu::Fail
    } else {
        AbsentQemu::Skip(format!(
            "NOTE: on-target test `{test}` did NOT run: `{QEMU_BINARY}` is not installed; {QEMU_INSTALL_HINT}"
        ))
    }
}

/// For tests and CI: the board ELF, built if needed, or `None` when QEMU is absent outside CI (after printing
/// plainly that the on-target test did not run and how to install QEMU). Under `CI=true`, an absent QEMU or a
/// failed build is an error (the caller's test fails).
pub fn board_for_tests(test: &str) -> Result<Option<PathBuf>, QemuError> {
    static BUILT: std::sync::OnceLock<Result<PathBuf, String>> = std::sync::OnceLock::new();
    let ci = std::env::var("CI").ok();
    match absent_qemu_policy(qemu_available(), ci.as_deref(), test) {
        AbsentQemu::Run => {}
        AbsentQemu::Skip(note) => {
            eprintln!("{note}");
            return Ok(None);
        }
        AbsentQemu::Fail => return Err(QemuError::NotInstalled),
    }
    let built = BUILT.get_or_init(|| {
        if std::env::var_os("TETHERBOT_BOARD_ELF").is_some() {
            return Ok(board_elf_path());
        }
        build_board_elf().map_err(|e| e.to_string())
    });
    match built {
        Ok(p) => Ok(Some(p.clone())),
        Err(e) => Err(QemuError::BuildFailed(e.clone())),
    }
}
