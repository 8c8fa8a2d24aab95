use naocalib::detect::{self, DetectOptions};
use naocalib::model::Model;
use naocalib::sim::render::{ImageOutput, RenderOptions};
use naocalib::sim::{SimOptions, simulate};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = args[1].parse().unwrap();
    let stances: usize = args[2].parse().unwrap();
    let cap: u64 = args[3].parse().unwrap();
    let dir = std::path::PathBuf::from(format!("/tmp/dbg_{seed}_{stances}"));
    let options = SimOptions { seed, stances, heads: 3, px_noise: 0.0, near_border: true,
        images: Some(ImageOutput { dir: dir.clone(), options: RenderOptions { seed, ..RenderOptions::default() }, force: true }),
        ..SimOptions::default() };
    let mut d = simulate(&Model::default(), &options).unwrap();
    d.dir = dir;
    let c = d.captures.iter().find(|c| c.id == cap).unwrap().clone();
    let truth = d.corners_by_capture();
    for t in &truth[&cap] { eprintln!("truth {:?} {:?}", t.vertex, t.pixel); }
    let r = detect::detect_capture(&d, &c, &DetectOptions { guided: std::env::var_os("CB").is_none(), ..DetectOptions::default() });
    eprintln!("{r}");
    if let detect::Outcome::Found { corners, .. } = &r.outcome {
        for k in corners { eprintln!("det {:?} {:?}", k.vertex, k.pixel); }
    }
}
