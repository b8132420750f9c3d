//! dfp-profirust-peer: profirust's FDL active station (token ring, GAP) and DP master class 1
//! with one DP slave, as an independent peer of dfp-sim on a tty or PTY. It brings the slave to
//! Data_Exchange, keeps it there for --seconds or --rotations token receipts, and prints a JSON
//! summary (README.md). Exit 0 only when the slave reached Data_Exchange and stayed there.

mod args;
mod pty;
mod tap;

use profirust::dp;
use profirust::fdl::{self, live_list, FdlApplication};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: libc::c_int) {
    STOP.store(true, Ordering::SeqCst);
}

/// profirust logs through `log`: warnings and errors are the only way it reports trouble
/// (token not taken, unexpected telegram, slave not answering), so they are kept for the summary.
struct Logger {
    level: log::LevelFilter,
    kept: Mutex<(u64, Vec<String>)>,
}

const KEPT_MESSAGES: usize = 20;

impl log::Log for Logger {
    fn enabled(&self, m: &log::Metadata) -> bool {
        m.level() <= self.level || m.level() <= log::Level::Warn
    }
    fn log(&self, r: &log::Record) {
        if r.level() <= log::Level::Warn {
            let mut k = self.kept.lock().unwrap();
            k.0 += 1;
            if k.1.len() < KEPT_MESSAGES {
                k.1.push(format!("{}: {}", r.level(), r.args()));
            }
        }
        if r.level() <= self.level {
            eprintln!(
                "dfp-profirust-peer: {} {}: {}",
                r.level(),
                r.target(),
                r.args()
            );
        }
    }
    fn flush(&self) {}
}

/// profirust's LiveList probes one address per token visit, and an absent address costs a whole
/// slot time: on a PTY (a slot time of 100 ms) that would slow every rotation. This lets one probe
/// through per --live-interval and passes everything else to LiveList unchanged.
struct Throttled {
    inner: live_list::LiveList,
    interval: profirust::time::Duration,
    last: Option<profirust::time::Instant>,
    busy: bool,
}

impl FdlApplication for Throttled {
    fn transmit_telegram(
        &mut self,
        now: profirust::time::Instant,
        fdl: &fdl::FdlActiveStation,
        tx: fdl::TelegramTx,
        high_prio_only: bool,
    ) -> Option<fdl::TelegramTxResponse> {
        if !self.busy && (high_prio_only || self.last.is_some_and(|l| now - l < self.interval)) {
            return None;
        }
        let r = self.inner.transmit_telegram(now, fdl, tx, high_prio_only);
        self.busy = r.is_some();
        if self.busy {
            self.last = Some(now);
        }
        r
    }
    fn receive_reply(
        &mut self,
        now: profirust::time::Instant,
        fdl: &fdl::FdlActiveStation,
        addr: u8,
        t: fdl::Telegram,
    ) {
        self.inner.receive_reply(now, fdl, addr, t)
    }
    fn handle_timeout(
        &mut self,
        now: profirust::time::Instant,
        fdl: &fdl::FdlActiveStation,
        addr: u8,
    ) {
        self.inner.handle_timeout(now, fdl, addr)
    }
}

#[derive(Default)]
struct Slave {
    dx_cycles: u64,
    events: BTreeMap<&'static str, u64>,
    first_dx_us: Option<i64>,
    left_dx: Vec<String>,
}

fn event_name(e: dp::PeripheralEvent) -> &'static str {
    match e {
        dp::PeripheralEvent::Online => "online",
        dp::PeripheralEvent::Configured => "configured",
        dp::PeripheralEvent::ConfigError => "config_error",
        dp::PeripheralEvent::ParameterError => "parameter_error",
        dp::PeripheralEvent::DataExchanged => "data_exchanged",
        dp::PeripheralEvent::Diagnostics => "diagnostics",
        dp::PeripheralEvent::Offline => "offline",
    }
}

fn state_name(s: &fdl::ResponseState) -> &'static str {
    match s {
        fdl::ResponseState::Slave => "slave",
        fdl::ResponseState::MasterNotReady => "master_not_ready",
        fdl::ResponseState::MasterWithoutToken => "master_ready_to_enter",
        fdl::ResponseState::MasterInRing => "master_in_ring",
    }
}

fn js(s: &str) -> String {
    let mut o = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => o.push_str(&format!("\\u{:04x}", c as u32)),
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

fn fail_usage(msg: &str) -> ! {
    eprintln!("dfp-profirust-peer: {msg}");
    std::process::exit(2)
}

fn fail(msg: &str) -> ! {
    eprintln!("dfp-profirust-peer: {msg}");
    std::process::exit(1)
}

/// A PTY gets the peer's own PHY, a real tty profirust's Linux one (README.md, "The PHY").
enum Phy {
    Pty(pty::PtyPhy),
    Tty(profirust::phy::LinuxRs485Phy),
}

impl profirust::phy::ProfibusPhy for Phy {
    fn poll_transmission(&mut self, now: profirust::time::Instant) -> bool {
        match self {
            Phy::Pty(p) => p.poll_transmission(now),
            Phy::Tty(p) => p.poll_transmission(now),
        }
    }
    fn transmit_data<F, R>(&mut self, now: profirust::time::Instant, f: F) -> R
    where
        F: FnOnce(&mut [u8]) -> (usize, R),
    {
        match self {
            Phy::Pty(p) => p.transmit_data(now, f),
            Phy::Tty(p) => p.transmit_data(now, f),
        }
    }
    fn receive_data<F, R>(&mut self, now: profirust::time::Instant, f: F) -> R
    where
        F: FnOnce(&[u8]) -> (usize, R),
    {
        match self {
            Phy::Pty(p) => p.receive_data(now, f),
            Phy::Tty(p) => p.receive_data(now, f),
        }
    }
}

/// Opens DEV as profirust's Linux phy would (read-write, non-blocking) so that a bad device is
/// one line, not one of its panics: it must exist, open and be a tty.
fn open_port(port: &str, baud: profirust::Baudrate) -> (Phy, &'static str) {
    use std::os::unix::fs::OpenOptionsExt;
    use std::os::unix::io::{AsRawFd, IntoRawFd};
    let f = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(port)
        .unwrap_or_else(|e| fail(&format!("--port {port}: {e}")));
    if unsafe { libc::isatty(f.as_raw_fd()) } != 1 {
        fail(&format!("--port {port}: not a tty or PTY"));
    }
    if pty::is_pty(f.as_raw_fd()) {
        let p = pty::PtyPhy::new(f.into_raw_fd())
            .unwrap_or_else(|e| fail(&format!("--port {port}: {e}")));
        (Phy::Pty(p), "pty (the peer's own)")
    } else {
        drop(f);
        // LinuxRs485Phy reports a tty it cannot set up (termios2, 8E1, the rate) by panicking.
        std::panic::set_hook(Box::new(|_| {}));
        let phy = std::panic::catch_unwind(|| profirust::phy::LinuxRs485Phy::new(port, baud));
        let _ = std::panic::take_hook();
        let phy = phy.unwrap_or_else(|e| {
            let why = e
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| e.downcast_ref::<&str>().copied())
                .unwrap_or("unknown");
            fail(&format!(
                "--port {port}: profirust's LinuxRs485Phy refused it: {why}"
            ))
        });
        (Phy::Tty(phy), "profirust LinuxRs485Phy")
    }
}

fn main() {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let a = match args::parse(&argv) {
        Ok(args::Parsed::Run(a)) => a,
        Ok(args::Parsed::Help) => {
            println!("{}", args::USAGE);
            return;
        }
        Err(e) => fail_usage(&e),
    };
    let logger: &'static Logger = Box::leak(Box::new(Logger {
        level: a.log_level,
        kept: Mutex::new((0, Vec::new())),
    }));
    log::set_logger(logger).unwrap();
    log::set_max_level(a.log_level.max(log::LevelFilter::Warn));

    let capture = a
        .capture
        .as_ref()
        .map(|p| std::fs::File::create(p).unwrap_or_else(|e| fail(&format!("--capture {p}: {e}"))));
    unsafe {
        libc::signal(libc::SIGINT, on_signal as *const () as libc::sighandler_t);
        libc::signal(libc::SIGTERM, on_signal as *const () as libc::sighandler_t);
    }

    let mut dp_master = dp::DpMaster::new(vec![]);
    let options = dp::PeripheralOptions {
        ident_number: a.ident,
        user_parameters: Some(&a.prm),
        config: Some(&a.cfg),
        max_tsdr: args::gsd_max_tsdr(a.baud),
        fail_safe: true,
        ..Default::default()
    };
    let mut pi_i = vec![0u8; a.inputs];
    let mut pi_q = vec![0u8; a.outputs];
    let mut diag = vec![0u8; 64];
    let handle = dp_master.add(
        dp::Peripheral::new(a.slave, options, &mut pi_i[..], &mut pi_q[..])
            .with_diag_buffer(&mut diag[..]),
    );

    let mut pb = fdl::ParametersBuilder::new(a.address, a.baud);
    // highest_station_address() also sets TTR (5000 x HSA): an explicit --ttr-bits comes after.
    if let Some(h) = a.hsa {
        pb.highest_station_address(h);
    }
    if let Some(t) = a.ttr_bits {
        pb.token_rotation_bits(t);
    }
    if let Some(s) = a.slot_bits {
        pb.slot_bits(s);
    }
    if let Some(g) = a.gap {
        pb.gap_wait_rotations(g);
    }
    if let Some(r) = a.max_retry {
        pb.max_retry_limit(r);
    }
    let mut fdl = fdl::FdlActiveStation::new(pb.build_verified(&dp_master));
    let p = fdl.parameters().clone();

    let clock = std::time::Instant::now();
    // A monotonic clock: profirust's Instant::now() follows the wall clock (SystemTime).
    let now = || profirust::time::Instant::from_micros(clock.elapsed().as_micros() as i64 + 1);
    let t0 = now();
    let (phy, phy_name) = open_port(&a.port, a.baud);
    let mut phy = tap::Tap::new(phy, a.address, t0, capture);
    let mut live = Throttled {
        inner: live_list::LiveList::new(),
        interval: profirust::time::Duration::from_millis(a.live_interval_ms),
        last: None,
        busy: false,
    };
    let mut seen: BTreeMap<u8, &'static str> = BTreeMap::new();
    let mut lost: Vec<u8> = Vec::new();
    let mut slave = Slave::default();
    let end = t0 + profirust::time::Duration::from_micros((a.seconds * 1e6) as u64);

    fdl.set_online();
    dp_master.enter_operate();
    let panic_msg: std::sync::Arc<Mutex<Option<String>>> = Default::default();
    {
        let pm = panic_msg.clone();
        std::panic::set_hook(Box::new(move |info| {
            *pm.lock().unwrap() = Some(info.to_string().replace('\n', " "));
        }));
    }
    let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| loop {
        let t = now();
        if STOP.load(Ordering::SeqCst)
            || t >= end
            || (a.rotations != 0 && phy.wire.receipts >= a.rotations)
        {
            break;
        }
        fdl.poll_multi(t, &mut phy, &mut [&mut dp_master, &mut live]);
        let ev = dp_master.take_last_events();
        if let Some((_, e)) = ev.peripheral {
            *slave.events.entry(event_name(e)).or_default() += 1;
            match e {
                dp::PeripheralEvent::DataExchanged => {
                    slave.dx_cycles += 1;
                    slave
                        .first_dx_us
                        .get_or_insert((t - t0).total_micros() as i64);
                }
                dp::PeripheralEvent::Offline
                | dp::PeripheralEvent::ConfigError
                | dp::PeripheralEvent::ParameterError
                    if slave.first_dx_us.is_some() =>
                {
                    slave.left_dx.push(format!(
                        "{} at {} us, after {} Data_Exchange cycles",
                        event_name(e),
                        (t - t0).total_micros(),
                        slave.dx_cycles
                    ));
                }
                _ => {}
            }
        }
        match live.inner.take_last_event() {
            Some(live_list::StationEvent::Discovered(d)) => {
                seen.insert(d.address, state_name(&d.state));
            }
            Some(live_list::StationEvent::Lost(addr)) => {
                seen.remove(&addr);
                lost.push(addr);
            }
            None => {}
        }
        std::thread::sleep(std::time::Duration::from_micros(500));
    }));
    phy.flush();
    let elapsed_us = (now() - t0).total_micros();

    let ring = fdl.inspect_token_ring();
    let las: Vec<u8> = ring.iter_active_stations().collect();
    let periph = dp_master.get_mut(handle);
    let running = periph.is_running();
    let slave_state = if running {
        "data_exchange"
    } else if periph.is_live() {
        "not_in_data_exchange"
    } else {
        "offline"
    };
    let diag_flags = periph.last_diagnostics().map(|d| format!("{:?}", d.flags));
    let inputs = periph
        .pi_i()
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect::<String>();

    // The live list as profirust reports it: LiveList's answers (its Request FDL Status sweep
    // over 0..125) with the station type they give, and the stations of the token ring's LAS,
    // which are active by definition (this station is always in it).
    let mut live_all: BTreeMap<u8, (String, Vec<&str>)> = BTreeMap::new();
    for (addr, st) in &seen {
        let kind = if *st == "slave" { "passive" } else { "active" };
        live_all.insert(
            *addr,
            (
                format!("{{\"address\": {addr}, \"type\": \"{kind}\", \"fdl_status\": \"{st}\""),
                vec!["live_list"],
            ),
        );
    }
    for addr in &las {
        live_all
            .entry(*addr)
            .or_insert_with(|| {
                (
                    format!("{{\"address\": {addr}, \"type\": \"active\", \"fdl_status\": null"),
                    vec![],
                )
            })
            .1
            .push("las");
    }
    let live_json: Vec<String> = live_all
        .values()
        .map(|(head, from)| {
            let f: Vec<String> = from.iter().map(|s| js(s)).collect();
            format!("{head}, \"from\": [{}]}}", f.join(", "))
        })
        .collect();

    let mut errors: Vec<String> = Vec::new();
    let panicked = run.is_err();
    if panicked {
        let m = panic_msg
            .lock()
            .unwrap()
            .clone()
            .unwrap_or_else(|| "unknown".into());
        errors.push(format!("profirust stopped (panic): {m}"));
    }
    if let Some(e) = &phy.wire.first_error {
        errors.push(e.clone());
    }
    errors.extend(
        slave
            .left_dx
            .iter()
            .map(|s| format!("the slave left Data_Exchange: {s}")),
    );
    let (warnings, kept) = {
        let k = logger.kept.lock().unwrap();
        (k.0, k.1.clone())
    };
    errors.extend(kept);
    let ok = !panicked && running && slave.first_dx_us.is_some() && slave.left_dx.is_empty();

    let w = &phy.wire;
    let ev: Vec<String> = slave
        .events
        .iter()
        .map(|(k, v)| format!("{}: {v}", js(k)))
        .collect();
    let err: Vec<String> = errors.iter().map(|e| js(e)).collect();
    let las_s: Vec<String> = las.iter().map(|x| x.to_string()).collect();
    let holders: Vec<String> = w.token_holders.iter().map(|x| x.to_string()).collect();
    let lost_s: Vec<String> = lost.iter().map(|x| x.to_string()).collect();
    let json = format!(
        "{{\n  \"ok\": {ok},\n  \"profirust\": \"0.6.0\",\n  \"port\": {},\n  \"phy\": {},\n  \"address\": {},\n  \
         \"baud\": {},\n  \"elapsed_us\": {elapsed_us},\n  \"stopped_by\": {},\n  \
         \"bus_parameters\": {{\"slot_bits\": {}, \"ttr_bits\": {}, \"gap\": {}, \"hsa\": {}, \
         \"max_retry\": {}, \"min_tsdr_bits\": {}, \"token_lost_timeout_us\": {}}},\n  \
         \"in_ring\": {},\n  \"next_station\": {},\n  \"previous_station\": {},\n  \
         \"las\": [{}],\n  \"live_list\": [\n    {}\n  ],\n  \"live_list_lost\": [{}],\n  \
         \"slave\": {{\"address\": {}, \"state\": \"{slave_state}\", \"dx_cycles\": {}, \
         \"first_dx_us\": {}, \"inputs\": \"{inputs}\", \"diagnostics\": {}, \"events\": {{{}}}}},\n  \
         \"token\": {{\"api\": \"profirust 0.6.0 exposes no token or rotation counter: these are \
         counted on the wire by the peer\", \"receipts\": {}, \"received\": {}, \
         \"passed_to_self\": {}, \"sent\": {}, \"between_others\": {}, \"holders_heard\": [{}], \
         \"rotation_us\": {{\"min\": {}, \"mean\": {}, \"max\": {}}}}},\n  \
         \"fdl_status\": {{\"requests_sent\": {}, \"replies_sent\": {}, \"requests_received\": {}}},\n  \
         \"telegrams\": {{\"sent\": {}, \"received\": {}, \"bad_frames\": {}, \"bad_bytes\": {}}},\n  \
         \"warnings\": {warnings},\n  \"errors\": [{}]\n}}\n",
        js(&a.port),
        js(phy_name),
        a.address,
        a.baud.to_rate(),
        js(if panicked {
            "panic"
        } else if STOP.load(Ordering::SeqCst) {
            "signal"
        } else if a.rotations != 0 && w.receipts >= a.rotations {
            "rotations"
        } else {
            "time"
        }),
        p.slot_bits,
        p.token_rotation_bits,
        p.gap_wait_rotations,
        p.highest_station_address,
        p.max_retry_limit,
        p.min_tsdr_bits,
        p.token_lost_timeout().total_micros(),
        fdl.is_in_ring(),
        ring.next_station(),
        ring.previous_station(),
        las_s.join(", "),
        live_json.join(",\n    "),
        lost_s.join(", "),
        a.slave,
        slave.dx_cycles,
        slave.first_dx_us.map_or("null".into(), |x| x.to_string()),
        diag_flags.map_or("null".into(), |d| js(&d)),
        ev.join(", "),
        w.receipts,
        w.tokens_received,
        w.tokens_to_self,
        w.tokens_sent,
        w.tokens_between_others,
        holders.join(", "),
        w.rotation_min_us,
        w.rotation_mean_us(),
        w.rotation_max_us,
        w.status_requests_sent,
        w.status_replies_sent,
        w.status_requests_received,
        w.tx_telegrams,
        w.rx_telegrams,
        w.rx_bad_frames,
        w.rx_bad_bytes,
        err.join(", "),
    );
    print!("{json}");
    if let Some(path) = &a.json {
        if let Err(e) = std::fs::write(path, &json) {
            fail(&format!("--json {path}: {e}"));
        }
    }
    std::process::exit(if ok { 0 } else { 1 });
}
