//! The `s3://bucket/prefix` remote (cargo feature `s3`): presigned requests (rusty-s3, no I/O of
//! its own) sent with a small blocking HTTP client (ureq), so no async runtime is built in.
//!
//! Configured by the usual environment only: `AWS_ACCESS_KEY_ID`, `AWS_SECRET_ACCESS_KEY`,
//! `AWS_SESSION_TOKEN`, `AWS_REGION` or `AWS_DEFAULT_REGION` (default `us-east-1`), and
//! `AWS_ENDPOINT_URL` or `AWS_ENDPOINT` for a non-AWS server (path-style URLs, `http://` allowed).
//! Without credentials requests are unsigned (an anonymous, read-only cache of a public bucket).
//! Create-if-absent is `PUT` with `If-None-Match: *` (412 when the object exists).

use super::backend::{Backend, RemoteError};
use crate::engine::error::EngineError;
use rusty_s3::{Bucket, Credentials, S3Action, UrlStyle};
use std::time::Duration;

pub struct S3Remote {
    url: String,
    bucket: Bucket,
    prefix: String,
    credentials: Option<Credentials>,
    agent: ureq::Agent,
}

const SIGN_FOR: Duration = Duration::from_secs(600);

fn env(names: &[&str]) -> Option<String> {
    names
        .iter()
        .find_map(|n| std::env::var(n).ok().filter(|v| !v.is_empty()))
}

impl S3Remote {
    /// `rest` is what follows `s3://`: `bucket` or `bucket/prefix`.
    pub fn from_env(url: &str, rest: &str) -> Result<S3Remote, EngineError> {
        let (name, prefix) = rest.split_once('/').unwrap_or((rest, ""));
        if name.is_empty() {
            return Err(EngineError::Usage(format!(
                "remote `{url}` names no bucket; write s3://bucket/prefix"
            )));
        }
        let region =
            env(&["AWS_REGION", "AWS_DEFAULT_REGION"]).unwrap_or_else(|| "us-east-1".into());
        let (endpoint, style) = match env(&["AWS_ENDPOINT_URL", "AWS_ENDPOINT"]) {
            Some(e) => (e, UrlStyle::Path),
            None => (
                format!("https://s3.{region}.amazonaws.com"),
                UrlStyle::VirtualHost,
            ),
        };
        let endpoint_url = endpoint.parse().map_err(|e| {
            EngineError::Usage(format!(
                "AWS_ENDPOINT_URL `{endpoint}` is not a URL ({e}); write e.g. http://127.0.0.1:9000"
            ))
        })?;
        let bucket = Bucket::new(endpoint_url, style, name.to_string(), region).map_err(|e| {
            EngineError::Usage(format!(
                "remote `{url}`: {e}; check the bucket name and AWS_ENDPOINT_URL"
            ))
        })?;
        let credentials = match (env(&["AWS_ACCESS_KEY_ID"]), env(&["AWS_SECRET_ACCESS_KEY"])) {
            (Some(k), Some(s)) => Some(match env(&["AWS_SESSION_TOKEN"]) {
                Some(t) => Credentials::new_with_token(k, s, t),
                None => Credentials::new(k, s),
            }),
            _ => None,
        };
        let agent: ureq::Agent = ureq::Agent::config_builder()
            .http_status_as_error(false)
            .timeout_connect(Some(Duration::from_secs(5)))
            .timeout_global(Some(Duration::from_secs(120)))
            .build()
            .into();
        let prefix = prefix.trim_matches('/');
        Ok(S3Remote {
            url: url.to_string(),
            bucket,
            prefix: if prefix.is_empty() {
                String::new()
            } else {
                format!("{prefix}/")
            },
            credentials,
            agent,
        })
    }

    fn object(&self, name: &str) -> String {
        format!("{}{name}", self.prefix)
    }

    fn refused(&self, status: u16, what: &str) -> RemoteError {
        let m = format!("{what} refused with HTTP {status}");
        match status {
            401 | 403 => RemoteError::Unavailable(m),
            _ => RemoteError::Other(m),
        }
    }
}

fn transport(e: ureq::Error) -> RemoteError {
    match e {
        ureq::Error::Io(_)
        | ureq::Error::ConnectionFailed
        | ureq::Error::HostNotFound
        | ureq::Error::Timeout(_) => RemoteError::Unavailable(format!("cannot reach it: {e}")),
        e => RemoteError::Other(e.to_string()),
    }
}

impl Backend for S3Remote {
    fn describe(&self) -> String {
        self.url.clone()
    }

    fn get(&self, name: &str) -> Result<Option<Vec<u8>>, RemoteError> {
        let object = self.object(name);
        let url = self
            .bucket
            .get_object(self.credentials.as_ref(), &object)
            .sign(SIGN_FOR);
        let mut resp = self.agent.get(url.as_str()).call().map_err(transport)?;
        match resp.status().as_u16() {
            200 => resp
                .body_mut()
                .with_config()
                .limit(u64::MAX)
                .read_to_vec()
                .map(Some)
                .map_err(transport),
            404 => Ok(None),
            s => Err(self.refused(s, "GET")),
        }
    }

    fn exists(&self, name: &str) -> Result<bool, RemoteError> {
        let object = self.object(name);
        let url = self
            .bucket
            .head_object(self.credentials.as_ref(), &object)
            .sign(SIGN_FOR);
        let resp = self.agent.head(url.as_str()).call().map_err(transport)?;
        match resp.status().as_u16() {
            200 => Ok(true),
            404 => Ok(false),
            s => Err(self.refused(s, "HEAD")),
        }
    }

    fn put_if_absent(&self, name: &str, bytes: &[u8]) -> Result<bool, RemoteError> {
        let object = self.object(name);
        let mut action = self.bucket.put_object(self.credentials.as_ref(), &object);
        action.headers_mut().insert("if-none-match", "*");
        let url = action.sign(SIGN_FOR);
        let resp = self
            .agent
            .put(url.as_str())
            .header("if-none-match", "*")
            .send(bytes)
            .map_err(transport)?;
        match resp.status().as_u16() {
            200 | 201 | 204 => Ok(true),
            // 412: it exists; 409: another writer is creating it right now
            412 | 409 => Ok(false),
            s => Err(self.refused(s, "PUT")),
        }
    }

    fn put_overwrite(&self, name: &str, bytes: &[u8]) -> Result<(), RemoteError> {
        let object = self.object(name);
        let url = self
            .bucket
            .put_object(self.credentials.as_ref(), &object)
            .sign(SIGN_FOR);
        let resp = self
            .agent
            .put(url.as_str())
            .send(bytes)
            .map_err(transport)?;
        match resp.status().as_u16() {
            200 | 201 | 204 => Ok(()),
            s => Err(self.refused(s, "PUT")),
        }
    }

    fn hint(&self) -> String {
        if self.credentials.is_none() {
            "set AWS_ACCESS_KEY_ID and AWS_SECRET_ACCESS_KEY (and AWS_ENDPOINT_URL for a non-AWS server), or use --remote-read-only for a public bucket".into()
        } else {
            "check AWS_ACCESS_KEY_ID, AWS_SECRET_ACCESS_KEY, AWS_REGION and AWS_ENDPOINT_URL, and that the bucket exists and grants GetObject, PutObject and ListBucket (so misses are 404, not 403; groove never lists)".into()
        }
    }
}
