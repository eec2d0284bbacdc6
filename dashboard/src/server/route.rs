//! What each path answers: the page, its script and style (compiled into the binary), the
//! latest image and snapshot, and `/events` (served by `events.rs`). Only GET and HEAD.

use super::reply::{Body, Reply};
use crate::hub::Hub;

const INDEX_HTML: &str = include_str!("../assets/index.html");
const APP_JS: &str = include_str!("../assets/app.js");
const STYLE_CSS: &str = include_str!("../assets/style.css");

pub enum Route {
    Reply(Reply),
    /// The server-sent-event stream of snapshots.
    Events,
}

pub fn route(method: &str, path: &str, hub: &Hub) -> Route {
    if !matches!(method, "GET" | "HEAD") {
        return Route::Reply(Reply::text(405, "read-only: GET only\n"));
    }
    let asset =
        |content_type, text| Route::Reply(Reply::new(200, content_type, Body::Static(text)));
    match path {
        "/" | "/index.html" => asset("text/html; charset=utf-8", INDEX_HTML),
        "/app.js" => asset("text/javascript; charset=utf-8", APP_JS),
        "/style.css" => asset("text/css; charset=utf-8", STYLE_CSS),
        "/image.png" => Route::Reply(match hub.png() {
            Some(png) => Reply::new(200, "image/png", Body::Bytes(png)),
            None => Reply::text(404, "no image yet\n"),
        }),
        "/snapshot.json" => Route::Reply(match hub.latest() {
            Some(s) => Reply::new(200, "application/json", Body::Shared(s)),
            None => Reply::text(503, "no snapshot yet\n"),
        }),
        "/events" => Route::Events,
        _ => Route::Reply(Reply::text(404, "not found\n")),
    }
}
