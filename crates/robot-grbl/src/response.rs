//! GRBL 1.1's answers, one line each (`doc/markdown/interface.md` of gnea/grbl): `ok`,
//! `error:N`, `ALARM:N`, status reports `<…>`, the welcome banner, settings `$N=V`, and the
//! bracketed feedback and push messages `[…]`.

/// The machine state in a status report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum State {
    /// Nothing to do.
    Idle,
    /// Running motion.
    Run,
    /// Feed hold: `Hold:1` while decelerating, `Hold:0` when stopped (`sub` in [`Status`]).
    Hold,
    /// Jogging.
    Jog,
    /// Alarm: G-code is locked out until `$X` or `$H`.
    Alarm,
    /// The safety door is open (or closing).
    Door,
    /// Check mode (`$C`): G-code is parsed but nothing moves.
    Check,
    /// Homing.
    Home,
    /// Sleeping (`$SLP`).
    Sleep,
}

impl State {
    fn parse(s: &str) -> Option<State> {
        Some(match s {
            "Idle" => State::Idle,
            "Run" => State::Run,
            "Hold" => State::Hold,
            "Jog" => State::Jog,
            "Alarm" => State::Alarm,
            "Door" => State::Door,
            "Check" => State::Check,
            "Home" => State::Home,
            "Sleep" => State::Sleep,
            _ => return None,
        })
    }
}

/// A status report (`<Idle|MPos:0.000,0.000,0.000|FS:0,0>`): the fields maobi reads.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Status {
    /// The state.
    pub state: State,
    /// The sub-state after `:` (`Hold:0` is 0), if any.
    pub sub: Option<u8>,
    /// Machine position, mm (`MPos`), when the report gives it.
    pub mpos: Option<[f64; 3]>,
    /// Work position, mm (`WPos`), when the report gives it.
    pub wpos: Option<[f64; 3]>,
    /// The work coordinate offset, mm (`WCO`), in the reports that carry it.
    pub wco: Option<[f64; 3]>,
    /// Planner blocks and receive-buffer bytes free (`Bf`), when reported.
    pub buffer: Option<(u32, u32)>,
}

impl Status {
    /// The machine position, from `MPos`, or from `WPos` and the work offset `wco`.
    pub fn machine(&self, wco: [f64; 3]) -> Option<[f64; 3]> {
        self.mpos.or_else(|| self.wpos.map(|w| [w[0] + wco[0], w[1] + wco[1], w[2] + wco[2]]))
    }

    /// The state as GRBL writes it (`Hold:0`).
    pub fn state_text(&self) -> String {
        match self.sub {
            Some(s) => format!("{:?}:{s}", self.state),
            None => format!("{:?}", self.state),
        }
    }
}

/// One line from GRBL.
#[derive(Clone, Debug, PartialEq)]
pub enum Response {
    /// `ok`: a line was executed or planned.
    Ok,
    /// `error:N`: a line was refused.
    Error(u16),
    /// `ALARM:N`.
    Alarm(u16),
    /// A status report.
    Status(Status),
    /// The welcome banner `Grbl 1.1h ['$' for help]`: the version (`1.1h`).
    Banner(String),
    /// A setting `$N=V`.
    Setting(u16, f64),
    /// A bracketed message `[…]`: its content (`VER:1.1h.20190830:`, `MSG:Pgm End`,
    /// `G54:0.000,0.000,0.000`, `GC:G0 G54 …`).
    Bracket(String),
    /// Anything else (an echo, a startup line `>G21:ok`, noise on the line).
    Other(String),
}

/// A number as GRBL prints it (`-12.500`, `500`): finite decimals only.
fn number(s: &str) -> Option<f64> {
    let body = s.strip_prefix('-').unwrap_or(s);
    if body.is_empty() || !body.bytes().all(|b| b.is_ascii_digit() || b == b'.') || body.matches('.').count() > 1 {
        return None;
    }
    s.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Three comma-separated numbers (a position).
fn triple(s: &str) -> Option<[f64; 3]> {
    let mut it = s.split(',');
    let v = [number(it.next()?)?, number(it.next()?)?, number(it.next()?)?];
    // GRBL with more axes reports more; maobi drives X, Y, Z.
    Some(v)
}

fn status(body: &str) -> Option<Status> {
    let mut fields = body.split('|');
    let head = fields.next()?;
    let (name, sub) = match head.split_once(':') {
        Some((n, s)) => (n, Some(s.parse::<u8>().ok()?)),
        None => (head, None),
    };
    let mut st = Status { state: State::parse(name)?, sub, mpos: None, wpos: None, wco: None, buffer: None };
    for f in fields {
        let Some((key, value)) = f.split_once(':') else { continue };
        match key {
            "MPos" => st.mpos = Some(triple(value)?),
            "WPos" => st.wpos = Some(triple(value)?),
            "WCO" => st.wco = Some(triple(value)?),
            "Bf" => {
                let (a, b) = value.split_once(',')?;
                st.buffer = Some((a.parse().ok()?, b.parse().ok()?));
            }
            _ => {}
        }
    }
    Some(st)
}

impl Response {
    /// Reads one line (without its line end). A line that looks like one of the kinds but does
    /// not parse (a status report cut or garbled) is [`Response::Other`].
    ///
    /// # Examples
    /// ```
    /// use robot_grbl::{Response, State};
    /// assert_eq!(Response::parse("ok"), Response::Ok);
    /// assert_eq!(Response::parse("error:22"), Response::Error(22));
    /// assert_eq!(Response::parse("Grbl 1.1h ['$' for help]"), Response::Banner("1.1h".into()));
    /// let Response::Status(s) = Response::parse("<Hold:0|MPos:1.000,-2.500,3.000|FS:0,0>") else { panic!() };
    /// assert_eq!((s.state, s.sub, s.mpos), (State::Hold, Some(0), Some([1.0, -2.5, 3.0])));
    /// ```
    pub fn parse(line: &str) -> Response {
        let line = line.trim_end_matches(['\r', '\n']);
        if line == "ok" {
            return Response::Ok;
        }
        if let Some(code) = line.strip_prefix("error:").and_then(|c| c.parse().ok()) {
            return Response::Error(code);
        }
        if let Some(code) = line.strip_prefix("ALARM:").and_then(|c| c.parse().ok()) {
            return Response::Alarm(code);
        }
        if let Some(body) = line.strip_prefix('<').and_then(|l| l.strip_suffix('>'))
            && let Some(s) = status(body)
        {
            return Response::Status(s);
        }
        if let Some(rest) = line.strip_prefix("Grbl ")
            && let Some((version, _)) = rest.split_once(' ')
        {
            return Response::Banner(version.to_string());
        }
        if let Some(body) = line.strip_prefix('$')
            && let Some((n, v)) = body.split_once('=')
            && let (Ok(n), Some(v)) = (n.parse(), number(v))
        {
            return Response::Setting(n, v);
        }
        if let Some(body) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            return Response::Bracket(body.to_string());
        }
        Response::Other(line.to_string())
    }
}

/// A bracketed `[NAME:x,y,z]` position (`G54:…`, `G92:…`) or `[TLO:z]`: its name and values.
pub(crate) fn offset(body: &str) -> Option<(&str, Vec<f64>)> {
    let (name, rest) = body.split_once(':')?;
    // `[PRB:x,y,z:1]` carries a flag after the position.
    let values = rest.split(':').next()?;
    let v: Option<Vec<f64>> = values.split(',').map(number).collect();
    Some((name, v?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_of_every_kind_are_read_and_garbled_ones_are_not_taken_for_them() {
        assert_eq!(Response::parse("ok\r"), Response::Ok);
        assert_eq!(Response::parse("ALARM:3"), Response::Alarm(3));
        assert_eq!(Response::parse("$110=500.000"), Response::Setting(110, 500.0));
        assert_eq!(Response::parse("$13=0"), Response::Setting(13, 0.0));
        assert_eq!(Response::parse("[MSG:Pgm End]"), Response::Bracket("MSG:Pgm End".into()));
        let Response::Status(s) =
            Response::parse("<Run|WPos:10.000,-5.000,-1.250|Bf:15,128|FS:600,0|WCO:-100.000,-20.000,-30.000>")
        else {
            panic!("not a status")
        };
        assert_eq!(s.state, State::Run);
        assert_eq!(s.wpos, Some([10.0, -5.0, -1.25]));
        assert_eq!(s.buffer, Some((15, 128)));
        assert_eq!(s.machine(s.wco.unwrap()), Some([-90.0, -25.0, -31.25]));
        // Garbled as a noisy line or a racing simulator can print them.
        for bad in [
            "<Idle|MPos:20.000,15.000,,.000|FS:0,0>",
            "<Run|MPos:13.280,102452|FS:2498,0>",
            "<Idle|MPos:1.0,2.0,inf>",
            "<Walk|MPos:0.000,0.000,0.000>",
            "<Idle|MPos:0.000,0.000,0.000",
            "error:x",
            "okay",
        ] {
            assert!(matches!(Response::parse(bad), Response::Other(_)), "{bad}");
        }
        assert_eq!(offset("G54:-10.000,-20.000,-5.500"), Some(("G54", vec![-10.0, -20.0, -5.5])));
        assert_eq!(offset("PRB:0.000,0.000,0.000:0"), Some(("PRB", vec![0.0, 0.0, 0.0])));
        assert_eq!(offset("TLO:1.500"), Some(("TLO", vec![1.5])));
    }
}
