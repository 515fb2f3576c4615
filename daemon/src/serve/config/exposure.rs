//! Warnings at start for a daemon bound beyond loopback that other machines still cannot
//! control (issue 37): `serve --control 0.0.0.0:9011` with the default `control_allow`.

use super::Config;

impl Config {
    /// One warning per socket bound beyond loopback whose control `control_allow` still
    /// refuses from other machines (the control socket; the monitor page, whose controls obey
    /// `control_allow` too), each saying what to pass. Empty when nothing is at odds.
    pub fn exposure_warnings(&self) -> Vec<String> {
        if !self.control_allow.loopback_only() {
            return Vec::new();
        }
        let fix = "pass --control-allow with their network (e.g. --control-allow 192.168.1.0/24) \
                   or set control_allow in the config";
        let mut out = Vec::new();
        if !self.control.ip().is_loopback() {
            out.push(format!(
                "control listens on {} but control_allow admits this host only ({}): control \
                 from other machines is refused; {fix}",
                self.control, self.control_allow
            ));
        }
        if let Some(monitor) = self.monitor.filter(|m| !m.ip().is_loopback()) {
            out.push(format!(
                "the monitor page listens on {monitor} but control_allow admits this host only \
                 ({}): on other machines the page is view-only; {fix}",
                self.control_allow
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::super::RawConfig;

    fn config(control: &str, monitor: Option<&str>, allow: Option<&[&str]>) -> super::Config {
        RawConfig {
            model: Some("m.json".into()),
            control: Some(control.into()),
            monitor: monitor.map(Into::into),
            monitor_token: monitor.map(|_| "secret-token-1234".into()),
            control_allow: allow.map(|a| a.iter().map(|s| s.to_string()).collect()),
            ..RawConfig::default()
        }
        .validate()
        .expect("valid")
    }

    #[test]
    fn control_and_monitor_beyond_loopback_with_loopback_control_warn() {
        let w = config("0.0.0.0:9011", Some("0.0.0.0:9081"), None).exposure_warnings();
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(w[0].starts_with("control listens on 0.0.0.0:9011"), "{w:?}");
        assert!(
            w[1].contains("view-only") && w[1].contains("--control-allow"),
            "{w:?}"
        );
    }

    #[test]
    fn loopback_binds_or_a_wider_allow_list_do_not_warn() {
        assert!(config("127.0.0.1:9011", Some("127.0.0.1:9081"), None)
            .exposure_warnings()
            .is_empty());
        assert!(config(
            "0.0.0.0:9011",
            Some("0.0.0.0:9081"),
            Some(&["192.168.1.0/24"])
        )
        .exposure_warnings()
        .is_empty());
    }
}
