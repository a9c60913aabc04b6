//! The page's files, embedded in the binary at build time (no network
//! needed: no CDN, no web fonts).

macro_rules! web {
    ($($path:literal => $ctype:literal),* $(,)?) => {
        /// (URL path, content type, bytes) of every embedded file.
        const FILES: &[(&str, &str, &[u8])] = &[
            $((concat!("/", $path), $ctype, include_bytes!(concat!("../../web/", $path)))),*
        ];
    };
}

web! {
    "index.html" => "text/html; charset=utf-8",
    "style.css" => "text/css; charset=utf-8",
    "main.js" => "text/javascript; charset=utf-8",
    "api.js" => "text/javascript; charset=utf-8",
    "viewer.js" => "text/javascript; charset=utf-8",
    "camera.js" => "text/javascript; charset=utf-8",
    "lights.js" => "text/javascript; charset=utf-8",
    "picking.js" => "text/javascript; charset=utf-8",
    "panels.js" => "text/javascript; charset=utf-8",
    "colormap.js" => "text/javascript; charset=utf-8",
    "uvpanel.js" => "text/javascript; charset=utf-8",
    "tools.js" => "text/javascript; charset=utf-8",
    "shortcuts.js" => "text/javascript; charset=utf-8",
    "help.js" => "text/javascript; charset=utf-8",
    "docframes.js" => "text/javascript; charset=utf-8",
    "capture.js" => "text/javascript; charset=utf-8",
    "views.js" => "text/javascript; charset=utf-8",
    "shape.js" => "text/javascript; charset=utf-8",
    "surfacetools.js" => "text/javascript; charset=utf-8",
    "session.js" => "text/javascript; charset=utf-8",
    "shaders/surface.vert" => "text/plain; charset=utf-8",
    "shaders/surface.frag" => "text/plain; charset=utf-8",
    "shaders/pick.vert" => "text/plain; charset=utf-8",
    "shaders/pick.frag" => "text/plain; charset=utf-8",
    "shaders/line.vert" => "text/plain; charset=utf-8",
    "shaders/line.frag" => "text/plain; charset=utf-8",
}

/// The content type and bytes of the page file at URL path `path` ("/" is
/// the page itself).
pub fn asset(path: &str) -> Option<(&'static str, &'static [u8])> {
    let path = if path == "/" { "/index.html" } else { path };
    FILES
        .iter()
        .find(|(p, _, _)| *p == path)
        .map(|(_, c, b)| (*c, *b))
}
