//! `tetherbot`: the operator's CLI (run a scenario, campaign, record, replay, export, render).

fn main() {
    println!("tetherbot: not yet implemented");
}
