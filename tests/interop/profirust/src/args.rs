//! The command line: one table of options, parsed into `Args`, every value checked here so that
//! profirust's own asserts (ParametersBuilder panics on a bad value) are never reached.

use profirust::Baudrate;

pub const USAGE: &str = "\
usage: dfp-profirust-peer --port DEV --slave ADDR [options]
  profirust's FDL active station and DP master (class 1) with one DP slave on a tty or PTY
  --port DEV            the tty or PTY (a link to it is fine)
  --address A           this master's FDL address, 0..125 (2)
  --baud B              9600, 19200, 45450, 93750, 187500, 500k, 1.5M, 3M, 6M (19200)
  --slave ADDR          the DP slave's address, 0..125, not A
  --ident N             the slave's ident number (0x6003, the DFP21B)
  --prm HEX             Set_Prm user data (000000068100000101, the DFP21B's GSD defaults)
  --cfg HEX             Chk_Cfg bytes (F3F2, \"Param + 3 PD\"); they also give the I/O sizes
  --slot-bits N         TSL in bit times (profirust's per rate: 100 up to 187.5k ... 600 at 6M)
  --ttr-bits N          TTR in bit times, 256..16777960 (32436, or 5000 x HSA with --hsa)
  --gap N               GAP update factor G in rotations, 1..100 (10)
  --hsa N               highest station address, A+1..126 (126)
  --max-retry N         retry limit, 1..15 (1)
  --seconds S           run this long, 0.1..86400 (10)
  --rotations N         or stop after N token receipts (0: time only)
  --live-interval MS    at most one live-list probe (Request FDL Status) per MS ms (100)
  --json OUT            write the summary there too (it always goes to stdout)
  --capture FILE        every telegram sent and received, one line each, decoded
  --log LEVEL           profirust's log on stderr: off, error, warn, info, debug, trace (warn)
  -h, --help            this text
exit: 0 when the slave reached Data_Exchange and stayed there, 1 when not (or the port failed),
2 on a bad argument";

pub struct Args {
    pub port: String,
    pub address: u8,
    pub baud: Baudrate,
    pub slave: u8,
    pub ident: u16,
    pub prm: Vec<u8>,
    pub cfg: Vec<u8>,
    pub inputs: usize,
    pub outputs: usize,
    pub slot_bits: Option<u16>,
    pub ttr_bits: Option<u32>,
    pub gap: Option<u8>,
    pub hsa: Option<u8>,
    pub max_retry: Option<u8>,
    pub seconds: f64,
    pub rotations: u64,
    pub live_interval_ms: u64,
    pub json: Option<String>,
    pub capture: Option<String>,
    pub log_level: log::LevelFilter,
}

pub enum Parsed {
    Run(Args),
    Help,
}

fn number(opt: &str, v: &str, min: u64, max: u64) -> Result<u64, String> {
    let n = if let Some(h) = v.strip_prefix("0x").or_else(|| v.strip_prefix("0X")) {
        u64::from_str_radix(h, 16)
    } else {
        v.parse::<u64>()
    };
    match n {
        Ok(n) if n >= min && n <= max => Ok(n),
        Ok(n) => Err(format!("{opt} {n}: out of range {min}..{max}")),
        Err(_) => Err(format!("{opt} '{v}': not a number")),
    }
}

fn hex(opt: &str, v: &str, max: usize) -> Result<Vec<u8>, String> {
    let v: String = v.chars().filter(|c| *c != ' ' && *c != ':').collect();
    if v.len() % 2 != 0 || !v.chars().all(|c| c.is_ascii_hexdigit()) {
        return Err(format!("{opt} '{v}': not an even number of hex digits"));
    }
    let bytes: Vec<u8> = (0..v.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&v[i..i + 2], 16).unwrap())
        .collect();
    if bytes.len() > max {
        return Err(format!("{opt}: {} bytes, at most {max}", bytes.len()));
    }
    Ok(bytes)
}

pub fn baud(v: &str) -> Result<Baudrate, String> {
    Ok(match v.to_ascii_lowercase().as_str() {
        "9600" | "9.6k" => Baudrate::B9600,
        "19200" | "19.2k" => Baudrate::B19200,
        "45450" | "45.45k" => Baudrate::B45450,
        "93750" | "93.75k" => Baudrate::B93750,
        "187500" | "187.5k" => Baudrate::B187500,
        "500000" | "500k" => Baudrate::B500000,
        "1500000" | "1.5m" => Baudrate::B1500000,
        "3000000" | "3m" => Baudrate::B3000000,
        "6000000" | "6m" => Baudrate::B6000000,
        "12000000" | "12m" => {
            return Err("--baud 12M: the DFP21B does not support it (GSD 12M_supp = 0)".into())
        }
        _ => {
            return Err(format!(
                "--baud '{v}': not a PROFIBUS rate the DFP21B supports"
            ))
        }
    })
}

/// profirust's smallest slot time per rate (fdl/parameters.rs, min_slot_bits): its
/// ParametersBuilder::slot_bits asserts against it.
pub fn min_slot_bits(b: Baudrate) -> u16 {
    match b {
        Baudrate::B500000 => 200,
        Baudrate::B1500000 => 300,
        Baudrate::B3000000 => 400,
        Baudrate::B6000000 => 600,
        Baudrate::B12000000 => 1000,
        _ => 100,
    }
}

/// MaxTsdr_* of firmware/gsd/SEW_6003.GSD: the slot time must exceed it (profirust wants 15 bit
/// times more in build_verified).
pub fn gsd_max_tsdr(b: Baudrate) -> u16 {
    match b {
        Baudrate::B500000 => 32,
        Baudrate::B1500000 => 96,
        Baudrate::B3000000 => 192,
        Baudrate::B6000000 => 383,
        _ => 15,
    }
}

/// Input and output bytes of a Chk_Cfg (IEC 61158-6-3 identifier bytes, compact and special
/// format), as the slave will exchange them.
pub fn io_sizes(cfg: &[u8]) -> Result<(usize, usize), String> {
    let (mut inp, mut out) = (0usize, 0usize);
    let mut i = 0;
    while i < cfg.len() {
        let b = cfg[i];
        i += 1;
        if b & 0x30 != 0 {
            let n = ((b & 0x0F) as usize + 1) * if b & 0x40 != 0 { 2 } else { 1 };
            if b & 0x10 != 0 {
                inp += n;
            }
            if b & 0x20 != 0 {
                out += n;
            }
            continue;
        }
        if b & 0xC0 == 0 && b & 0x0F == 0 {
            continue; // an empty slot
        }
        // Special format: length bytes for outputs then inputs, then manufacturer data.
        let mut len_byte = |sum: &mut usize| -> Result<(), String> {
            let l = *cfg.get(i).ok_or("--cfg: special identifier cut short")?;
            i += 1;
            *sum += ((l & 0x3F) as usize + 1) * if l & 0x40 != 0 { 2 } else { 1 };
            Ok(())
        };
        if b & 0x80 != 0 {
            len_byte(&mut out)?;
        }
        if b & 0x40 != 0 {
            len_byte(&mut inp)?;
        }
        i += (b & 0x0F) as usize;
        if i > cfg.len() {
            return Err("--cfg: manufacturer data of a special identifier cut short".into());
        }
    }
    if inp > 244 || out > 244 {
        return Err(format!(
            "--cfg: {inp} input / {out} output bytes, at most 244 each"
        ));
    }
    Ok((inp, out))
}

pub fn parse(argv: &[String]) -> Result<Parsed, String> {
    let mut port = None;
    let mut slave = None;
    let mut a = Args {
        port: String::new(),
        address: 2,
        baud: Baudrate::B19200,
        slave: 0,
        ident: 0x6003,
        prm: hex("--prm", "000000068100000101", 237)?,
        cfg: vec![0xF3, 0xF2],
        inputs: 0,
        outputs: 0,
        slot_bits: None,
        ttr_bits: None,
        gap: None,
        hsa: None,
        max_retry: None,
        seconds: 10.0,
        rotations: 0,
        live_interval_ms: 100,
        json: None,
        capture: None,
        log_level: log::LevelFilter::Warn,
    };
    let mut it = argv.iter();
    while let Some(opt) = it.next() {
        let opt = opt.as_str();
        if opt == "-h" || opt == "--help" {
            return Ok(Parsed::Help);
        }
        if !opt.starts_with("--") {
            return Err(format!("unexpected argument '{opt}' (see --help)"));
        }
        let v = it
            .next()
            .ok_or_else(|| format!("{opt} needs a value"))?
            .as_str();
        match opt {
            "--port" => port = Some(v.to_string()),
            "--address" => a.address = number(opt, v, 0, 125)? as u8,
            "--baud" => a.baud = baud(v)?,
            "--slave" => slave = Some(number(opt, v, 0, 125)? as u8),
            "--ident" => a.ident = number(opt, v, 0, 0xFFFF)? as u16,
            "--prm" => a.prm = hex(opt, v, 237)?,
            "--cfg" => a.cfg = hex(opt, v, 244)?,
            "--slot-bits" => a.slot_bits = Some(number(opt, v, 1, 65535)? as u16),
            "--ttr-bits" => a.ttr_bits = Some(number(opt, v, 256, 16_777_960)? as u32),
            "--gap" => a.gap = Some(number(opt, v, 1, 100)? as u8),
            "--hsa" => a.hsa = Some(number(opt, v, 1, 126)? as u8),
            "--max-retry" => a.max_retry = Some(number(opt, v, 1, 15)? as u8),
            "--seconds" => {
                a.seconds = match v.parse::<f64>() {
                    Ok(s) if (0.1..=86400.0).contains(&s) => s,
                    _ => return Err(format!("--seconds '{v}': not a time of 0.1..86400 s")),
                }
            }
            "--rotations" => a.rotations = number(opt, v, 0, u32::MAX as u64)?,
            "--live-interval" => a.live_interval_ms = number(opt, v, 0, 3_600_000)?,
            "--json" => a.json = Some(v.to_string()),
            "--capture" => a.capture = Some(v.to_string()),
            "--log" => {
                a.log_level = v.parse().map_err(|_| {
                    format!("--log '{v}': not one of off, error, warn, info, debug, trace")
                })?
            }
            _ => return Err(format!("unknown option '{opt}' (see --help)")),
        }
    }
    a.port = port.ok_or("--port DEV is required")?;
    a.slave = slave.ok_or("--slave ADDR is required")?;
    if a.slave == a.address {
        return Err(format!(
            "--slave {} is this master's own --address",
            a.slave
        ));
    }
    if a.cfg.is_empty() {
        return Err("--cfg: at least one identifier byte".into());
    }
    (a.inputs, a.outputs) = io_sizes(&a.cfg)?;
    let min = min_slot_bits(a.baud).max(gsd_max_tsdr(a.baud) + 15);
    if let Some(s) = a.slot_bits {
        if s < min {
            return Err(format!(
                "--slot-bits {s}: at this rate at least {min} (profirust's minimum, and the \
                 DFP21B's MaxTsdr + 15)"
            ));
        }
    }
    if let Some(h) = a.hsa {
        if h <= a.address {
            return Err(format!(
                "--hsa {h}: must be above this master's address {}",
                a.address
            ));
        }
    }
    Ok(Parsed::Run(a))
}
