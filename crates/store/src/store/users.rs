//! Users, passwords and login sessions.
use super::audit::audit;
use super::{Store, unix_now};
use crate::model::{Role, User};
use crate::{Result, StoreError, now_rfc3339};
use argon2::Argon2;
use argon2::password_hash::{PasswordHash, PasswordHasher, PasswordVerifier, SaltString};
use rand::RngCore;
use rusqlite::{OptionalExtension, params};

/// How long a login session lasts without use.
const SESSION_SECONDS: i64 = 30 * 24 * 3600;

/// Check a user name: 1..=64 printable characters, no leading/trailing space.
fn validate_name(name: &str) -> Result<()> {
    if name.is_empty() || name.chars().count() > 64 || name.trim() != name {
        return Err(StoreError::Invalid(
            "a user name has 1 to 64 characters and no surrounding spaces".into(),
        ));
    }
    // "consensus" names the combined tracing of all users in exports.
    if name.eq_ignore_ascii_case(crate::CONSENSUS) {
        return Err(StoreError::Invalid(format!(
            "'{name}' is reserved (it names the consensus of all users)"
        )));
    }
    if name
        .chars()
        .any(|c| c.is_control() || c == '/' || c == '\\')
    {
        return Err(StoreError::Invalid(
            "a user name may not contain control characters or slashes".into(),
        ));
    }
    Ok(())
}

/// The user called `name` in the open transaction, if any.
fn user_named(tx: &rusqlite::Transaction<'_>, name: &str) -> Result<Option<User>> {
    Ok(tx
        .prepare_cached("SELECT id, name, role, password_hash FROM users WHERE name = ?1")?
        .query_row([name], user_from_row)
        .optional()?)
}

pub(super) fn user_from_row(r: &rusqlite::Row<'_>) -> rusqlite::Result<User> {
    let role: String = r.get(2)?;
    Ok(User {
        id: r.get(0)?,
        name: r.get(1)?,
        role: Role::parse(&role).unwrap_or(Role::Tracer),
        has_password: r.get::<_, Option<String>>(3)?.is_some(),
    })
}

impl Store {
    /// The user called `name`, if any.
    pub fn user(&self, name: &str) -> Result<Option<User>> {
        self.read(|tx| user_named(tx, name))
    }

    /// Every user, by name.
    pub fn users(&self) -> Result<Vec<User>> {
        self.read(|tx| {
            let mut st =
                tx.prepare_cached("SELECT id, name, role, password_hash FROM users ORDER BY name")?;
            let rows = st.query_map([], user_from_row)?;
            Ok(rows.collect::<rusqlite::Result<_>>()?)
        })
    }

    /// Create a user, or update the role and password of an existing one.
    /// The password is stored as an argon2id hash.
    pub fn upsert_user(&self, name: &str, role: Role, password: Option<&str>) -> Result<User> {
        validate_name(name)?;
        let hash = match password {
            Some("") => {
                return Err(StoreError::Invalid("the password is empty".into()));
            }
            Some(p) => {
                let salt = SaltString::generate(&mut argon2::password_hash::rand_core::OsRng);
                Some(
                    Argon2::default()
                        .hash_password(p.as_bytes(), &salt)
                        .map_err(|e| StoreError::Invalid(format!("cannot hash password: {e}")))?
                        .to_string(),
                )
            }
            None => None,
        };
        self.write(|tx| {
            tx.prepare_cached(
                "INSERT INTO users (name, role, password_hash, created) VALUES (?1, ?2, ?3, ?4) \
                 ON CONFLICT(name) DO UPDATE SET role = excluded.role, \
                 password_hash = COALESCE(excluded.password_hash, users.password_hash)",
            )?
            .execute(params![name, role.as_str(), hash, now_rfc3339()])?;
            let user = user_named(tx, name)?.ok_or(rusqlite::Error::QueryReturnedNoRows)?;
            audit(
                tx,
                Some(user.id),
                None,
                "user.upsert",
                serde_json::json!({"name": name, "role": role.as_str(), "password_set": password.is_some()}),
            )?;
            Ok(user)
        })
    }

    /// The user called `name`, created as a tracer without password if missing
    /// (the loopback login, where a name is enough).
    pub fn ensure_user(&self, name: &str) -> Result<User> {
        validate_name(name)?;
        if let Some(u) = self.user(name)? {
            return Ok(u);
        }
        self.write(|tx| {
            tx.prepare_cached(
                "INSERT OR IGNORE INTO users (name, role, created) VALUES (?1, 'tracer', ?2)",
            )?
            .execute(params![name, now_rfc3339()])?;
            let user = user_named(tx, name)?.ok_or(rusqlite::Error::QueryReturnedNoRows)?;
            audit(
                tx,
                Some(user.id),
                None,
                "user.create",
                serde_json::json!({"name": name}),
            )?;
            Ok(user)
        })
    }

    /// Check a password; `BadCredentials` for an unknown user, a user without a
    /// password, or a wrong password (one message for all three).
    pub fn verify_password(&self, name: &str, password: &str) -> Result<User> {
        let row: Option<(User, Option<String>)> = self.read(|tx| {
            Ok(tx
                .prepare_cached("SELECT id, name, role, password_hash FROM users WHERE name = ?1")?
                .query_row([name], |r| Ok((user_from_row(r)?, r.get(3)?)))
                .optional()?)
        })?;
        let Some((user, Some(hash))) = row else {
            return Err(StoreError::BadCredentials);
        };
        let parsed = PasswordHash::new(&hash).map_err(|e| StoreError::Corrupt(e.to_string()))?;
        Argon2::default()
            .verify_password(password.as_bytes(), &parsed)
            .map_err(|_| StoreError::BadCredentials)?;
        Ok(user)
    }

    /// Start a login session, opened with a password or by name alone;
    /// returns its random token (256 bits, hex).
    pub fn create_session(&self, user_id: i64, with_password: bool) -> Result<String> {
        let mut bytes = [0u8; 32];
        rand::rngs::OsRng.fill_bytes(&mut bytes);
        let token: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
        self.write(|tx| {
            tx.prepare_cached("DELETE FROM sessions WHERE expires_unix < ?1")?
                .execute([unix_now()])?;
            tx.prepare_cached(
                "INSERT INTO sessions (token, user_id, created, expires_unix, with_password) \
                 VALUES (?1, ?2, ?3, ?4, ?5)",
            )?
            .execute(params![
                token,
                user_id,
                now_rfc3339(),
                unix_now() + SESSION_SECONDS,
                with_password
            ])?;
            audit(tx, Some(user_id), None, "login", serde_json::json!({}))?;
            Ok(token)
        })
    }

    /// The user of a live session token, and whether a password opened it.
    pub fn session_user(&self, token: &str) -> Result<Option<(User, bool)>> {
        self.read(|tx| {
            Ok(tx
                .prepare_cached(
                    "SELECT u.id, u.name, u.role, u.password_hash, s.with_password FROM sessions s \
                     JOIN users u ON u.id = s.user_id WHERE s.token = ?1 AND s.expires_unix >= ?2",
                )?
                .query_row(params![token, unix_now()], |r| {
                    Ok((user_from_row(r)?, r.get(4)?))
                })
                .optional()?)
        })
    }

    /// End a session (no error if it does not exist).
    pub fn delete_session(&self, token: &str) -> Result<()> {
        self.write(|tx| {
            tx.prepare_cached("DELETE FROM sessions WHERE token = ?1")?
                .execute([token])?;
            Ok(())
        })
    }
}
