//! One connection, on its own thread: request heads read and answered in turn (a bounded
//! keep-alive), or an event stream to its end, then a lingering close. Every read and write
//! has its deadline, so the thread ends whatever the viewer does.

use super::events;
use super::head::{self, NoRequest};
use super::limits::Limits;
use super::reply::Reply;
use super::route::{route, Route};
use super::timed::Timed;
use crate::hub::Hub;
use std::io::{self, BufReader, Read as _};
use std::net::{Shutdown, TcpStream};

pub fn serve(stream: TcpStream, hub: &Hub, limits: &Limits) {
    // Answers go out as written (an event is three writes).
    let _ = stream.set_nodelay(true);
    let mut reader = BufReader::new(Timed::new(&stream, limits.head_timeout));
    for answered in 1..=limits.requests_per_connection {
        if hub.stopped() {
            break;
        }
        reader.get_mut().renew(limits.head_timeout);
        let request = head::read(&mut reader, limits.max_head_bytes);
        let mut out = Timed::new(&stream, limits.write_timeout);
        let request = match request {
            Ok(request) => request,
            Err(no) => {
                if let Some(reply) = refusal(&no, limits) {
                    let _ = reply.write(&mut out, false, false);
                }
                break;
            }
        };
        let head_only = request.method == "HEAD";
        let keep_open = !request.close && answered < limits.requests_per_connection;
        let reply = match route(&request.method, &request.path, hub) {
            Route::Reply(reply) => reply,
            Route::Events => match hub.join(limits.max_viewers) {
                Some(viewer) => {
                    events::stream(&stream, hub, limits, head_only);
                    drop(viewer);
                    break;
                }
                None => Reply::text(
                    503,
                    format!("{} viewers already connected\n", limits.max_viewers),
                ),
            },
        };
        if reply.write(&mut out, head_only, keep_open).is_err() || !keep_open {
            break;
        }
    }
    linger_close(&stream, limits);
}

/// Beyond the connection limit: a 503 written without waiting (a new connection's buffer
/// takes it whole), then closed.
pub fn refuse_busy(stream: TcpStream, limits: &Limits) {
    let _ = stream.set_nonblocking(true);
    let text = format!("{} connections already open\n", limits.max_connections);
    let _ = Reply::text(503, text).write(&mut &stream, false, false);
}

fn refusal(no: &NoRequest, limits: &Limits) -> Option<Reply> {
    let text = match no {
        NoRequest::Gone => return None,
        NoRequest::Slow => format!(
            "request head not received within {} s\n",
            limits.head_timeout.as_secs_f64()
        ),
        NoRequest::TooLarge => {
            format!("request head longer than {} bytes\n", limits.max_head_bytes)
        }
        NoRequest::Malformed => "malformed request\n".to_string(),
    };
    Some(Reply::text(no.status()?, text))
}

/// After the last answer: nothing more is written, and what the viewer still sends is read and
/// dropped (bounded in bytes and time) so it reads the answer rather than a reset.
fn linger_close(stream: &TcpStream, limits: &Limits) {
    let _ = stream.shutdown(Shutdown::Write);
    let mut rest = Timed::new(stream, limits.linger_timeout).take(limits.linger_bytes as u64);
    let _ = io::copy(&mut rest, &mut io::sink());
}
