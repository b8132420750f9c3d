//! A PHY for a pseudo-terminal. Neither of profirust's Linux PHYs opens one: LinuxRs485Phy
//! asserts that the tty kept PARENB (fdl/phy/linux.rs), which a PTY clears, and SerialPortPhy
//! unwraps TIOCGSERIAL for low latency (serialport_low_latency), which a PTY refuses. A PTY has
//! neither parity nor a bit rate, so this one only makes it raw and non-blocking and moves bytes;
//! profirust itself times the line (it marks the bus busy for 11 bit times per byte sent).

use profirust::phy::ProfibusPhy;
use profirust::time::Instant;
use std::io;
use std::os::unix::io::RawFd;

const BUFFER: usize = 512;

pub struct PtyPhy {
    fd: RawFd,
    rx: Vec<u8>,
    rx_len: usize,
    tx: Vec<u8>,
    tx_done: usize,
}

/// True when `fd` is the slave side of a Unix 98 PTY (majors 136..143, devices.txt).
pub fn is_pty(fd: RawFd) -> bool {
    let mut st: libc::stat = unsafe { std::mem::zeroed() };
    if unsafe { libc::fstat(fd, &mut st) } != 0 {
        return false;
    }
    let major = libc::major(st.st_rdev);
    (st.st_mode & libc::S_IFMT) == libc::S_IFCHR && (136..=143).contains(&major)
}

fn check(what: &str, r: libc::c_int) -> io::Result<()> {
    if r < 0 {
        let e = io::Error::last_os_error();
        Err(io::Error::new(e.kind(), format!("{what}: {e}")))
    } else {
        Ok(())
    }
}

impl PtyPhy {
    /// Takes over `fd` (open read-write, non-blocking) and makes the PTY raw.
    pub fn new(fd: RawFd) -> io::Result<Self> {
        let mut t: libc::termios = unsafe { std::mem::zeroed() };
        check("tcgetattr", unsafe { libc::tcgetattr(fd, &mut t) })?;
        unsafe { libc::cfmakeraw(&mut t) };
        t.c_cc[libc::VMIN] = 0;
        t.c_cc[libc::VTIME] = 0;
        check("tcsetattr", unsafe {
            libc::tcsetattr(fd, libc::TCSANOW, &t)
        })?;
        Ok(PtyPhy {
            fd,
            rx: vec![0; BUFFER],
            rx_len: 0,
            tx: Vec::new(),
            tx_done: 0,
        })
    }

    /// Bytes written, 0 when the PTY is full; a hang-up (EIO) or other error stops the peer.
    fn write_some(&mut self) {
        let rest = &self.tx[self.tx_done..];
        let n = unsafe { libc::write(self.fd, rest.as_ptr() as *const libc::c_void, rest.len()) };
        if n < 0 {
            let e = io::Error::last_os_error();
            if e.kind() != io::ErrorKind::WouldBlock {
                panic!("write to the PTY: {e}");
            }
        } else {
            self.tx_done += n as usize;
        }
    }

    fn read_some(&mut self) {
        let room = &mut self.rx[self.rx_len..];
        if room.is_empty() {
            return;
        }
        let n = unsafe { libc::read(self.fd, room.as_mut_ptr() as *mut libc::c_void, room.len()) };
        if n < 0 {
            let e = io::Error::last_os_error();
            if e.kind() != io::ErrorKind::WouldBlock {
                panic!("read from the PTY: {e}");
            }
        } else {
            self.rx_len += n as usize;
        }
    }
}

impl Drop for PtyPhy {
    fn drop(&mut self) {
        unsafe { libc::close(self.fd) };
    }
}

impl ProfibusPhy for PtyPhy {
    fn poll_transmission(&mut self, _now: Instant) -> bool {
        if self.tx.is_empty() {
            return false;
        }
        if self.tx_done < self.tx.len() {
            self.write_some();
            return true;
        }
        self.tx.clear();
        self.tx_done = 0;
        false
    }

    fn transmit_data<F, R>(&mut self, _now: Instant, f: F) -> R
    where
        F: FnOnce(&mut [u8]) -> (usize, R),
    {
        assert!(self.tx.is_empty(), "transmit_data() while transmitting");
        let mut buf = [0u8; BUFFER];
        let (n, r) = f(&mut buf);
        if n > 0 {
            self.tx.extend_from_slice(&buf[..n]);
            self.write_some();
        }
        r
    }

    fn receive_data<F, R>(&mut self, _now: Instant, f: F) -> R
    where
        F: FnOnce(&[u8]) -> (usize, R),
    {
        assert!(self.tx.is_empty(), "receive_data() while transmitting");
        self.read_some();
        let (drop, r) = f(&self.rx[..self.rx_len]);
        let drop = drop.min(self.rx_len);
        self.rx.copy_within(drop..self.rx_len, 0);
        self.rx_len -= drop;
        r
    }
}
