//! How long `naocalib plan` takes to design a paper-sized schedule (144 captures of the
//! paper's 21 parameters, the default pool): as the command does by default, past the body
//! on naocalib's sandal; and as though the body hid nothing on the paper's board
//! (`--ignore-body`), with compliance and play freed too, and with both cameras and their
//! intrinsics (`--families paper,intrinsics --cameras lower,upper`); and how long ordering
//! its 144 captures along collision-free moves takes of that.

use criterion::{Criterion, criterion_group, criterion_main};

use naocalib::model::JointAngles;
use naocalib::model::{CameraId, Family, FixedSet, Model};
use naocalib::plan::{PlanOptions, collision::BodyModel, order, plan, route};

fn bench(c: &mut Criterion) {
    let model = Model::default();
    let mut group = c.benchmark_group("plan");
    group.sample_size(10);
    group.bench_function("plan_144_past_the_body", |b| {
        let sandal = Model::unconfigured();
        let mut options = PlanOptions::default();
        options.feasibility.sight = Some(naocalib::body::BodyModel::default());
        b.iter(|| plan(&sandal, &options).expect("plan"));
    });
    group.bench_function("plan_144_paper", |b| {
        let options = PlanOptions::default();
        b.iter(|| plan(&model, &options).expect("plan"));
    });
    group.bench_function("order_144_paper", |b| {
        let options = PlanOptions::default();
        let captures: Vec<JointAngles> = plan(&model, &options)
            .expect("plan")
            .captures
            .iter()
            .map(|c| c.joints)
            .collect();
        let (body, rest) = (BodyModel::default(), route::rest_posture());
        b.iter(|| order::order(&model, &body, &rest, &captures, &options.timing));
    });
    group.bench_function("plan_144_paper_compliance_play", |b| {
        let mut fixed = FixedSet::default();
        for family in [Family::Compliance, Family::Play] {
            for p in family.params() {
                fixed.set(p, false);
            }
        }
        let options = PlanOptions {
            fixed,
            ..PlanOptions::default()
        };
        b.iter(|| plan(&model, &options).expect("plan"));
    });
    group.bench_function("plan_144_both_cameras_intrinsics", |b| {
        let both = Model {
            upper_camera: Some(naocalib::sim::camera::CameraPreset::V6.camera()),
            ..Model::default()
        };
        let mut fixed = FixedSet::default();
        for p in Family::Intrinsics.params() {
            fixed.set(p, false);
        }
        let options = PlanOptions {
            fixed,
            cameras: CameraId::ALL.to_vec(),
            ..PlanOptions::default()
        };
        b.iter(|| plan(&both, &options).expect("plan"));
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
