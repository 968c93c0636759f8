//! Where a recording goes: a `.rrd` file, written beside its path and put
//! in place once the recording is finished, or a running viewer, checked
//! to listen before anything moves.

use std::net::{TcpStream, ToSocketAddrs};
use std::path::{Path, PathBuf};
use std::time::Duration;

use ::rerun::blueprint::{
    Blueprint, ContainerLike, Grid, Horizontal, Spatial3DView, TextLogView, TimeSeriesView,
    Vertical,
};
use ::rerun::{RecordingStream, RecordingStreamBuilder};

use super::scene::{GHOST, ROBOT};
use super::{RerunError, Sink};

/// The application a recording is of, in the viewer.
const APPLICATION: &str = "servobus";

/// How long a viewer may take to answer the check of its address.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(2);

/// How long the end of a recording may take to reach its file or viewer.
const FLUSH_TIMEOUT: Duration = Duration::from_secs(20);

/// An open recording and where it goes.
pub(super) struct Output {
    pub(super) stream: RecordingStream,
    place: Place,
}

/// Where an open recording is written.
enum Place {
    /// A temporary renamed over `target` when finished (`temp: None` once
    /// renamed, or for a target written in place).
    File {
        target: PathBuf,
        temp: Option<PathBuf>,
    },
    /// A viewer, at this address.
    Viewer(String),
}

impl Sink {
    /// Checks, before anything moves, that the recording can go where it
    /// is asked to: a file that can be written ([`crate::files::check_output`]),
    /// a viewer address that is a `rerun+http(s)://HOST:PORT/proxy` URL on
    /// which something listens.
    ///
    /// # Errors
    /// [`RerunError::Output`], [`RerunError::Address`] or
    /// [`RerunError::NoViewer`].
    pub fn check(&self) -> Result<(), RerunError> {
        match self {
            Sink::File(path) => Ok(crate::files::check_output(path)?),
            Sink::Viewer(address) => {
                let host = host_port(address)?;
                let reason = match host.to_socket_addrs() {
                    Ok(mut addrs) => match addrs.next() {
                        Some(addr) => match TcpStream::connect_timeout(&addr, CONNECT_TIMEOUT) {
                            Ok(_) => return Ok(()),
                            Err(e) => e.to_string(),
                        },
                        None => "the host has no address".to_owned(),
                    },
                    Err(e) => e.to_string(),
                };
                Err(RerunError::NoViewer {
                    address: address.clone(),
                    reason,
                })
            }
        }
    }
}

/// The `HOST:PORT` of a viewer's address.
fn host_port(address: &str) -> Result<String, RerunError> {
    let bad = |why: &str| RerunError::Address {
        address: address.to_owned(),
        reason: why.to_owned(),
    };
    let rest = ["rerun+http://", "rerun+https://", "rerun://"]
        .iter()
        .find_map(|scheme| address.strip_prefix(scheme))
        .ok_or_else(|| bad("it does not start with rerun+http://"))?;
    let (authority, path) = rest.split_once('/').unwrap_or((rest, ""));
    if path.trim_end_matches('/') != "proxy" {
        return Err(bad("a viewer's address ends in /proxy"));
    }
    let port = authority.rsplit_once(':').map(|(_, p)| p);
    match port.map(str::parse::<u16>) {
        Some(Ok(_)) => Ok(authority.to_owned()),
        _ => Err(bad("it names no port (the viewer's usual one is 9876)")),
    }
}

impl Output {
    /// Opens the recording `sink` asks for ([`Sink::check`] first), laid
    /// out for `joints` ([`layout`]).
    ///
    /// # Errors
    /// Those of [`Sink::check`]; [`RerunError::Start`] when the recording
    /// cannot be started.
    pub(super) fn open(sink: &Sink, joints: &[&str]) -> Result<Output, RerunError> {
        sink.check()?;
        let builder = RecordingStreamBuilder::new(APPLICATION).enabled(true);
        // A viewer that is running shows the new recording laid out so at
        // once; a file opens so unless the viewer was told otherwise.
        let builder = match sink {
            Sink::File(_) => builder.with_default_blueprint(layout(joints)),
            Sink::Viewer(_) => builder.with_blueprint(layout(joints)),
        };
        let start = |what: &str, e: &dyn std::fmt::Display| RerunError::Start {
            what: what.to_owned(),
            reason: e.to_string(),
        };
        match sink {
            Sink::File(target) => {
                let temp = temporary(target);
                let file = temp.as_deref().unwrap_or(target);
                let stream = builder
                    .save(file)
                    .map_err(|e| start(&target.display().to_string(), &e))?;
                Ok(Output {
                    stream,
                    place: Place::File {
                        target: target.clone(),
                        temp,
                    },
                })
            }
            Sink::Viewer(address) => {
                let stream = builder
                    .connect_grpc_opts(address.clone())
                    .map_err(|e| start(address, &e))?;
                Ok(Output {
                    stream,
                    place: Place::Viewer(address.clone()),
                })
            }
        }
    }

    /// Ends the recording: everything logged reaches the viewer, or the
    /// file is complete (its index written) and takes the target's place.
    ///
    /// # Errors
    /// [`RerunError::Finish`] when it could not be written or sent; a file
    /// target then keeps what it had.
    pub(super) fn finish(mut self) -> Result<(), RerunError> {
        let what = self.what();
        let flushed = self.stream.flush_with_timeout(FLUSH_TIMEOUT);
        // Dropping the stream ends the file (its footer) or the connection.
        let stream = std::mem::replace(&mut self.stream, RecordingStream::disabled());
        drop(stream);
        let failed = |reason: String| RerunError::Finish {
            what: what.clone(),
            reason,
        };
        flushed.map_err(|e| failed(e.to_string()))?;
        if let Place::File { target, temp } = &mut self.place {
            if let Some(from) = temp.take() {
                if let Err(e) = std::fs::rename(&from, &*target) {
                    let _ = std::fs::remove_file(&from);
                    return Err(failed(e.to_string()));
                }
            }
        }
        Ok(())
    }

    /// The file or viewer, as errors name it.
    pub(super) fn what(&self) -> String {
        match &self.place {
            Place::File { target, .. } => target.display().to_string(),
            Place::Viewer(address) => format!("the viewer at {address}"),
        }
    }
}

impl Drop for Output {
    fn drop(&mut self) {
        // Not finished: the target keeps what it had.
        if let Place::File {
            temp: Some(temp), ..
        } = &self.place
        {
            let stream = std::mem::replace(&mut self.stream, RecordingStream::disabled());
            drop(stream);
            let _ = std::fs::remove_file(temp);
        }
    }
}

/// How the viewer shows a recording unless told otherwise: the robot in
/// 3D, beside a plot of each of `joints`' series and the events.
fn layout(joints: &[&str]) -> Blueprint {
    let space = Spatial3DView::new("robot").with_origin("/").with_contents([
        format!("/{ROBOT}/**"),
        format!("/{GHOST}/**"),
        "/paths/**".to_owned(),
    ]);
    let plots = joints.iter().map(|j| {
        let at = super::scene::path("joints", [*j]);
        ContainerLike::from(TimeSeriesView::new(*j).with_origin(at))
    });
    let events = TextLogView::new("events").with_origin("/events");
    let side = Vertical::new([Grid::new(plots).into(), events.into()]).with_row_shares([4.0, 1.0]);
    Blueprint::new(Horizontal::new([space.into(), side.into()]).with_column_shares([3.0, 2.0]))
}

/// The temporary a recording to `target` is written to, beside it (one
/// file system, so that the rename is whole): `None` for a target that is
/// there and is no regular file (`/dev/null`, a FIFO), written in place.
fn temporary(target: &Path) -> Option<PathBuf> {
    if std::fs::metadata(target).is_ok_and(|m| !m.is_file()) {
        return None;
    }
    let name = target.file_name()?.to_string_lossy();
    let temp = format!(".{name}.{}.tmp", std::process::id());
    Some(target.with_file_name(temp))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_viewer_address_is_a_proxy_url_with_a_port() {
        assert_eq!(
            host_port(super::super::DEFAULT_VIEWER).expect("the default"),
            "127.0.0.1:9876"
        );
        assert_eq!(
            host_port("rerun+http://localhost:1234/proxy").expect("a port"),
            "localhost:1234"
        );
        for bad in [
            "http://127.0.0.1:9876/proxy",
            "rerun+http://127.0.0.1/proxy",
            "rerun+http://127.0.0.1:9876",
            "rerun+http://127.0.0.1:99999/proxy",
        ] {
            assert!(
                matches!(host_port(bad), Err(RerunError::Address { .. })),
                "{bad}"
            );
        }
    }

    #[test]
    fn no_viewer_on_a_port_is_said_before_anything_moves() {
        let port = {
            let l = std::net::TcpListener::bind("127.0.0.1:0").expect("bind");
            l.local_addr().expect("addr").port()
        };
        let sink = Sink::Viewer(format!("rerun+http://127.0.0.1:{port}/proxy"));
        let e = sink.check().expect_err("nothing listens");
        assert!(matches!(e, RerunError::NoViewer { .. }), "{e}");
        assert!(e.to_string().contains(&port.to_string()), "{e}");
    }
}
