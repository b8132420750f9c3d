//! A PHY in front of profirust's: every byte profirust hands to the line and every byte it takes
//! from it passes here, so the peer counts what profirust's API does not report (tokens sent and
//! received, token receipts and rotation times, FDL status telegrams, bad frames) and can write a
//! decoded capture. It changes nothing on the wire.

use profirust::phy::ProfibusPhy;
use profirust::time::Instant;
use std::collections::BTreeSet;
use std::io::Write;

const SD1: u8 = 0x10;
const SD2: u8 = 0x68;
const SD3: u8 = 0xA2;
const SD4: u8 = 0xDC;
const SC: u8 = 0xE5;
const ED: u8 = 0x16;

#[derive(Default)]
pub struct Wire {
    pub tx_telegrams: u64,
    pub rx_telegrams: u64,
    pub tokens_sent: u64,
    pub tokens_to_self: u64,
    pub tokens_received: u64,
    pub tokens_between_others: u64,
    pub status_requests_sent: u64,
    pub status_replies_sent: u64,
    pub status_requests_received: u64,
    pub rx_bad_frames: u64,
    pub rx_bad_bytes: u64,
    /// Token receipts: a token addressed to us heard on the line, or one we pass to ourselves.
    pub receipts: u64,
    last_receipt: Option<Instant>,
    pub rotation_min_us: i64,
    pub rotation_max_us: i64,
    pub rotation_sum_us: i64,
    /// Addresses heard passing a token (the token holders), ourselves included once we pass it.
    pub token_holders: BTreeSet<u8>,
    pub first_error: Option<String>,
}

impl Wire {
    fn receipt(&mut self, now: Instant) {
        if let Some(last) = self.last_receipt {
            let us = (now - last).total_micros() as i64;
            if self.receipts == 1 || us < self.rotation_min_us {
                self.rotation_min_us = us;
            }
            self.rotation_max_us = self.rotation_max_us.max(us);
            self.rotation_sum_us += us;
        }
        self.last_receipt = Some(now);
        self.receipts += 1;
    }

    pub fn rotation_mean_us(&self) -> i64 {
        if self.receipts > 1 {
            self.rotation_sum_us / (self.receipts as i64 - 1)
        } else {
            0
        }
    }
}

/// Length of the telegram at the start of `b`, None when it is not one (or is cut short).
fn frame_len(b: &[u8]) -> Option<usize> {
    let n = match *b.first()? {
        SC => return Some(1),
        SD4 => return if b.len() >= 3 { Some(3) } else { None },
        SD1 => 6,
        SD3 => 14,
        SD2 if b.len() >= 4 && b[1] == b[2] && b[3] == SD2 && b[1] >= 3 => b[1] as usize + 6,
        _ => return None,
    };
    if b.len() < n {
        return None;
    }
    let start = if b[0] == SD2 { 4 } else { 1 };
    let sum = b[start..n - 2].iter().fold(0u8, |s, x| s.wrapping_add(*x));
    if sum == b[n - 2] && b[n - 1] == ED {
        Some(n)
    } else {
        None
    }
}

/// A short reading of one telegram for the capture.
fn describe(b: &[u8]) -> String {
    match b[0] {
        SC => "SC (short acknowledgement)".into(),
        SD4 => format!("token {} -> {}", b[2], b[1]),
        _ => {
            let h = if b[0] == SD2 { 4 } else { 1 };
            let (da, sa, fc) = (b[h], b[h + 1], b[h + 2]);
            let saps = match (da & 0x80 != 0, sa & 0x80 != 0) {
                (true, true) => format!(" DSAP {} SSAP {}", b[h + 3], b[h + 4]),
                (true, false) => format!(" DSAP {}", b[h + 3]),
                (false, true) => format!(" SSAP {}", b[h + 3]),
                _ => String::new(),
            };
            let what = if fc & 0x40 != 0 {
                match fc & 0x0F {
                    9 => "Request FDL Status".to_string(),
                    12 => "SRD low".into(),
                    13 => "SRD high".into(),
                    4 => "SDN low".into(),
                    6 => "SDN high".into(),
                    3 => "SDA low".into(),
                    5 => "SDA high".into(),
                    14 => "Request Ident".into(),
                    f => format!("request {f}"),
                }
            } else {
                let st = [
                    "slave",
                    "master not ready",
                    "master ready to enter the ring",
                    "master in the ring",
                ][((fc >> 4) & 3) as usize];
                format!("response ({st}, status {})", fc & 0x0F)
            };
            format!("{} -> {} FC {:02X} {what}{saps}", sa & 0x7F, da & 0x7F, fc)
        }
    }
}

pub struct Tap<P: ProfibusPhy> {
    inner: P,
    own: u8,
    t0: Instant,
    pub wire: Wire,
    capture: Option<std::io::BufWriter<std::fs::File>>,
}

impl<P: ProfibusPhy> Tap<P> {
    pub fn new(inner: P, own: u8, t0: Instant, capture: Option<std::fs::File>) -> Self {
        Tap {
            inner,
            own,
            t0,
            wire: Wire::default(),
            capture: capture.map(std::io::BufWriter::new),
        }
    }

    pub fn flush(&mut self) {
        if let Some(c) = self.capture.as_mut() {
            let _ = c.flush();
        }
    }

    fn log(&mut self, now: Instant, dir: &str, b: &[u8], note: &str) {
        if let Some(c) = self.capture.as_mut() {
            let hex: Vec<String> = b.iter().map(|x| format!("{x:02X}")).collect();
            let _ = writeln!(
                c,
                "{:>10} {dir} {:<24} {note}",
                (now - self.t0).total_micros(),
                hex.join(" "),
            );
        }
    }

    fn sent(&mut self, now: Instant, b: &[u8]) {
        self.wire.tx_telegrams += 1;
        match b[0] {
            SD4 => {
                self.wire.tokens_sent += 1;
                self.wire.token_holders.insert(self.own);
                if b[1] == self.own {
                    self.wire.tokens_to_self += 1;
                    self.wire.receipt(now);
                }
            }
            SD1 if b[3] & 0x40 != 0 && b[3] & 0x0F == 9 => self.wire.status_requests_sent += 1,
            SD1 if b[3] & 0x40 == 0 && b[3] & 0x30 != 0 => self.wire.status_replies_sent += 1,
            _ => {}
        }
        let note = describe(b);
        self.log(now, "tx", b, &note);
    }

    fn received(&mut self, now: Instant, mut b: &[u8]) {
        while !b.is_empty() {
            let Some(n) = frame_len(b) else {
                self.wire.rx_bad_frames += 1;
                self.wire.rx_bad_bytes += b.len() as u64;
                if self.wire.first_error.is_none() {
                    let hex: Vec<String> = b.iter().take(16).map(|x| format!("{x:02X}")).collect();
                    self.wire.first_error = Some(format!(
                        "bad frame received at {} us: {}",
                        (now - self.t0).total_micros(),
                        hex.join(" ")
                    ));
                }
                let bytes = b.to_vec();
                self.log(now, "rx", &bytes, "NOT A TELEGRAM (dropped by profirust)");
                return;
            };
            let (f, rest) = b.split_at(n);
            self.wire.rx_telegrams += 1;
            match f[0] {
                SD4 => {
                    self.wire.token_holders.insert(f[2]);
                    if f[1] == self.own {
                        self.wire.tokens_received += 1;
                        self.wire.receipt(now);
                    } else {
                        self.wire.tokens_between_others += 1;
                    }
                }
                SD1 if f[1] == self.own && f[3] & 0x40 != 0 && f[3] & 0x0F == 9 => {
                    self.wire.status_requests_received += 1
                }
                _ => {}
            }
            let note = describe(f);
            self.log(now, "rx", f, &note);
            b = rest;
        }
    }
}

impl<P: ProfibusPhy> ProfibusPhy for Tap<P> {
    fn poll_transmission(&mut self, now: Instant) -> bool {
        self.inner.poll_transmission(now)
    }

    fn transmit_data<F, R>(&mut self, now: Instant, f: F) -> R
    where
        F: FnOnce(&mut [u8]) -> (usize, R),
    {
        let mut sent = Vec::new();
        let r = self.inner.transmit_data(now, |buf| {
            let (n, r) = f(buf);
            sent.extend_from_slice(&buf[..n]);
            (n, r)
        });
        if !sent.is_empty() {
            self.sent(now, &sent);
        }
        r
    }

    fn receive_data<F, R>(&mut self, now: Instant, f: F) -> R
    where
        F: FnOnce(&[u8]) -> (usize, R),
    {
        let mut taken = Vec::new();
        let r = self.inner.receive_data(now, |buf| {
            let (n, r) = f(buf);
            taken.extend_from_slice(&buf[..n]);
            (n, r)
        });
        if !taken.is_empty() {
            self.received(now, &taken);
        }
        r
    }
}
