//! The command-line front end of [`linercav::api::progress`]: a spinner with the current phase,
//! or a bar of counted steps, on an interactive terminal; nothing otherwise (CI logs and pipes
//! stay clean).

use indicatif::{ProgressBar, ProgressStyle};
use linercav::api::progress::Indicator;
use std::io::IsTerminal;
use std::time::Duration;

struct Bar(ProgressBar);

impl Indicator for Bar {
    fn phase(&self, msg: &str) {
        self.0.set_message(msg.to_string());
    }
    fn inc(&self) {
        self.0.inc(1);
    }
    fn finish(&self) {
        self.0.finish_and_clear();
    }
}

/// Makes the indicator of one computation (see [`linercav::api::progress::FrontEnd`]).
pub fn indicator(total: Option<u64>) -> Option<Box<dyn Indicator>> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = match total {
        None => {
            let b = ProgressBar::new_spinner();
            b.set_style(
                ProgressStyle::with_template("{spinner} {elapsed:>4} {msg}")
                    .expect("valid template"),
            );
            b.enable_steady_tick(Duration::from_millis(120));
            b
        }
        Some(n) => {
            let b = ProgressBar::new(n);
            b.set_style(
                ProgressStyle::with_template("{bar:30} {pos}/{len} runs, {elapsed} (eta {eta})")
                    .expect("valid template"),
            );
            b
        }
    };
    Some(Box::new(Bar(bar)))
}
