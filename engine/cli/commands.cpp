#include "engine/cli/commands.h"

#include "engine/cli/handlers.h"

namespace yelan::cli {

const std::vector<Command>& commands() {
  static const std::vector<Command> table = {
      {"run", "events -> 3D poses, live or from a file",
       "usage: yelan run --weights W FILE [--rate 50] [--out poses.csv|.json|.h5] [--beta B]\n"
       "       yelan run --weights W --camera [SERIAL] [--duration 10s] [same options]\n"
       "                 [--no-early-exit] [--height-mm 1700 | --depth-mm Z] [--keep-empty]\n"
       "                 [--threads T] [--stats-json S.json] [--viz DIR|OUT.mp4 [--viz-every N]] [--crop-margin PX]\n"
       "Per event the TORE volume; at each tick (--rate per second) stage 1 with early exit (the\n"
       "U-Net runs only when the stored future mask's score is below beta), the masked TORE\n"
       "through stage 2 (causal or windowed bidirectional, as the model's config says), and 13\n"
       "joints in mm in the camera frame, denormalised with a body-height prior for the depth\n"
       "(or a fixed --depth-mm). Ticks without events repeat the last pose (causal models).\n"
       "--beta: the model's (its config's run.beta; 0.99 if it has none) unless given.\n"
       "CSV columns: t_us, x,y,z of the 13 joints in SPEC order, confidence (P(person), from the\n"
       "mask's share of the frame through the model's calibration), mask_ran, person (0/1),\n"
       "pose_confidence (mean heatmap peak), mask_share. A pose without a person has no joints\n"
       "(empty CSV fields, null in JSON, NaN in HDF5).\n"
       "A file that ends mid-packet stops the run with a message; every pose computed is written.\n"
       "--camera: live from the attached DAVIS346/DVXplorer (the first, or the one with SERIAL;\n"
       "see `yelan devices`) until --duration or Ctrl-C (exit 0). CSV rows are written and\n"
       "flushed as poses are computed; a camera that stops sending (unplugged, USB error) ends\n"
       "the run with a message and exit 1, every pose computed written.\n"
       "--crop-margin PX: stage 2's ResNet head runs on the mask's bounding box grown by PX input\n"
       "pixels (0: the whole frame); default: the model's pose.crop_margin.\n"
       "--viz DIR: a PNG per pose (TORE and mask, projected skeleton, side view); DIR/run.mp4\n"
       "when ffmpeg is installed. --viz OUT.mp4: the same frames as a video at the pose rate\n"
       "(needs ffmpeg).\n",
       cmd_run, "streaming pose estimation (issue 8)"},
      {"sim", "simulate a dancer seen by an event camera, with labels",
       "usage: yelan sim --preset NAME|--config scene.json [--seed N] [--duration 2s] -o OUT.yelan.h5\n"
       "                 [--preview DIR [--preview-every 5]] [--threads T] [--quiet]\n"
       "       yelan sim --grid train|test|all --out-dir DIR [--duration 2s] [--seed N] [--limit N]\n"
       "                 [--characters a,b] [--motions m,..] [--views v,..] [--lights l,..] [--backgrounds b,..] [--force]\n"
       "       yelan sim --dataset DIR [--seed N] [--train 400] [--val 40] [--test 60] [--duration 5s] [--threads T]\n"
       "                 [--train-empty N] [--val-empty N] [--test-empty N] [--random-looks] [--frame-dancer]\n"
       "       yelan sim --list\n"
       "A character performs a CMU clip or a procedural dance in a scene; a ray caster renders\n"
       "it at an adaptive rate (>= 1 kHz) and a v2e-style pixel model makes the events. OUT holds\n"
       "the events, /camera (K, M), /labels (3D joints in the camera frame, 300 Hz), /masks\n"
       "(50 Hz) and the scene as attributes; the same arguments give the same bytes.\n"
       "Presets: <character>-<motion>-<view>-<light>-<bg> or <view>-<light>-<bg> (see --list).\n"
       "--grid writes one recording per grid member (existing files are kept unless --force)\n"
       "and DIR/manifest.json. --preview writes PNG frames and a contact sheet.\n"
       "--dataset writes DIR/{train,val,test}/*.yelan.h5 and DIR/manifest.json: whole clips with\n"
       "augmentation drawn per recording (mirror, speed 0.7-1.4x, start anywhere, yaw +-25 deg,\n"
       "distance, height, body and clothes, lighting, background, flicker, occluders); val holds\n"
       "out two training characters and the last 15% of each training clip, test uses the test\n"
       "characters and clips; --*-empty add scenes with nobody in them (rooms, moving backgrounds,\n"
       "flicker, occluders, noise, a panning or shaking camera: stage 1's negatives). Parallel\n"
       "over --threads (default: all cores); resumable (done files are kept); the same seed gives\n"
       "the same files. --random-looks: every training recording a new person (body, garment,\n"
       "hair, hat, skin and clothes' shades and patterns drawn per recording, named rXXXXX)\n"
       "instead of one of the nine training characters; val and test keep their cast.\n"
       "--frame-dancer: each dancer turned to face the view's way at the recording's start and\n"
       "centred in the picture on average (a clip started anywhere otherwise leaves the mocap\n"
       "subject wherever they had walked: a quarter of the joints out of the picture).\n"
       "Presets end in any of -occluded, -flicker, -pan (the camera sweeps +-6 deg every 8 s),\n"
       "-shake (a hand-held tremor) and -empty (nobody there).\n",
       cmd_sim, "the motion-to-event simulator (issue 6)"},
      {"train", "train the mask or pose network on CPU",
       "usage: yelan train --stage mask|pose --config NAME|FILE --sim PRESETS|train -o OUTDIR\n"
       "       yelan train --stage mask|pose --config NAME|FILE --data DIR [--val-data DIR] -o OUTDIR\n"
       "                   [--steps 1000] [--batch 8] [--epoch-steps 50] [--lr 1e-3] [--seed N]\n"
       "                   [--lr-schedule cosine|step] [--warmup-steps N] [--history 5] [--val-windows N]\n"
       "                   [--stop-at STEP] [--mask-frames F]\n"
       "                   [--occlusion] [--mask-weights W] [--init W] [--val-sim PRESETS]\n"
       "                   [--checkpoint-minutes 10] [--max-minutes M] [--max-cpu-minutes M] [--resume] [--threads T]\n"
       "Windows of S frames at 50 per second stream from the simulator (no disk): TORE read out\n"
       "at each frame, downscaled to the config's input. mask: the U-Net learns the current and\n"
       "N-1 future masks. pose: the pose net learns the normalised 3D joints from masked TORE\n"
       "(the mask from --mask-weights, frozen, or else the simulator's true mask).\n"
       "--data DIR: windows from the labelled recordings in DIR (*.yelan.h5, as yelan sim\n"
       "writes them) instead, frames on their mask times; validation on every tenth\n"
       "recording by name (split by recording, never by frame) or on --val-data DIR; a dataset\n"
       "folder (yelan sim --dataset) trains on DIR/train and validates on DIR/val. A window's TORE\n"
       "holds the events of up to --history seconds before it (5: all TORE reads, as yelan run).\n"
       "Adam (L2 1e-5); LR: cosine from --lr to 2% of it by step (after --warmup-steps), or\n"
       "--lr-schedule step: halved every 5 (mask) / 10 (pose) epochs; validation on other\n"
       "recordings each epoch, early stop after --patience 10 epochs. OUTDIR gets log.csv,\n"
       "checkpoint.h5 + checkpoint.state (atomic, every --checkpoint-minutes and at the end),\n"
       "best.h5 and final.h5; --resume continues from the checkpoint bit-exactly.\n"
       "--mask-frames F (mask stage): training windows of F frames instead of the config's S (the\n"
       "U-Net sees one frame at a time: windows of 1 frame give S times the distinct samples per\n"
       "step's cost); validation keeps S.\n",
       cmd_train, "the CPU trainer (issue 7)"},
      {"eval", "MPJPE, PCK@150 and AUC of a model on a test set",
       "usage: yelan eval --weights W --sim test|PRESETS|--data DIR [--seed N] [--scenes M] [--seconds 1]\n"
       "                  [--true-mask] [--history 5] [--no-floors] [--unframed] [--json OUT] [--threads T]\n"
       "       yelan eval --run --weights W --sim test [--seed N] [--scenes M] [--seconds 1] [--beta B] [--json OUT]\n"
       "Both networks as deployed on simulated scenes: --sim test draws M scenes of the test\n"
       "split (held-out characters and motions; views, lightings and backgrounds in turn)\n"
       "with seed N, each starting anywhere in its clip after --history s of events, so anyone\n"
       "can check a model on scenes it never saw; the dancer faces the view's way at the\n"
       "scene's start and stands centred in the picture (--unframed: the clip's own placement,\n"
       "as figures before this option were measured). --data DIR: the labelled recordings in DIR\n"
       "(*.yelan.h5), up to --seconds of each. A window's TORE holds the events of up to\n"
       "--history s before it (5: all TORE reads, as yelan run). Joints are denormalised with\n"
       "the true head depth (the paper protocol). Prints MPJPE, PCK@150, AUC (also\n"
       "root-aligned), per joint (n/a: never visible) and per condition, the mask IoU, the\n"
       "floors (trivial predictors on the same frames: constant, mean_pose_at_hip,\n"
       "per_view_mean_pose_at_hip) and per view the share of frames where swapping left and\n"
       "right would be better; --json OUT writes mpjpe_mm, pck150, auc, mpjpe_root_mm,\n"
       "frames, by_condition (also per scene), floors, swap_share_by_view, error_split\n"
       "(image-plane px and depth mm per joint, model and per-view floor), ....\n"
       "--run scores the deployed path instead: yelan run's pipeline on the same scenes (TORE of\n"
       "every event so far, stage 1 with early exit, depth from the body-height prior), each\n"
       "pose against the label at its time; JSON: deployed and paper (true head depth) scores.\n",
       cmd_eval, "evaluation (issue 7)"},
      {"convert", "convert an event file between formats",
       "usage: yelan convert IN OUT [--camera N]\n"
       "Reads any event file `yelan info` reads and writes OUT in the format its extension\n"
       "names: .yelan.h5/.h5 (ours), .aedat4 (AEDAT 4.0, LZ4) or .txt (`t_us x y p` lines).\n"
       "OUT is written atomically. Progress goes to stderr (a bar on a terminal).\n"
       "--camera N: only camera N (0..3, address & 0xF) of a DHP19 AEDAT 2.0 file.\n",
       cmd_convert, "event readers and writers (issue 5)"},
      {"info", "describe an event file",
       "usage: yelan info FILE [--json] [--camera N]\n"
       "Format, sensor size, event count, time span, event rate and polarity balance of an\n"
       "event file: Prophesee RAW (EVT 2.0/2.1/3.0), AEDAT 4.0/3.1/2.0, HDF5 (ours, DSEC,\n"
       "v2e), .npy or text. --json prints one object (keys format, width, height, events,\n"
       "on_events, t_first_us, t_last_us, ...). --camera N: one DHP19 camera (AEDAT 2.0).\n"
       "Bad input exits 2 with `yelan: error: FILE: offset N: problem`.\n",
       cmd_info, "event readers (issue 5)"},
      {"repr", "TORE volumes and baseline frames from an event file",
       "usage: yelan repr --type tore|tore-baldwin|count|voxel|surface (--at T1,T2,... | --fps F)\n"
       "                  [--k 3] [--tau-us US] [--window-us 20000] [--events 7500] [--bins 5]\n"
       "                  [--width W --height H] [--baf-us 70000] [--refractory-us US]\n"
       "                  [--png DIR] [--max-volumes 100000] [--quiet] IN OUT.h5\n"
       "Reads IN (any file `yelan info` reads) and writes OUT.h5 atomically: `volumes`\n"
       "(N x C x H x W float32) and `t` (N int64 us). A volume at T holds the events with t <= T.\n"
       "--at: absolute times in us, increasing. --fps F: every 1/F s after the first event, up\n"
       "to the last one. Types: tore (YeLan: C = 2K, pos0..pos{K-1} then neg0..neg{K-1}, 0 =\n"
       "newest; clamp(1 - ln(1+age)/ln(tau), 0, 0.7)/0.7, tau 5e6 us), tore-baldwin (the\n"
       "original log-age scaling), count (DHP19-normalised counts of the last --window-us, or\n"
       "of the last --events N), voxel (--bins over the last --window-us, polarity split\n"
       "linearly in time), surface (exp(-age/tau) per polarity, tau 50000 us).\n"
       "--baf-us / --refractory-us filter the events first. --png DIR: one picture per volume\n"
       "(TORE/surface: ON newest slot red, OFF blue; count grey; voxel newest bin +red/-blue).\n",
       cmd_repr, "representations (issue 5)"},
      {"record", "record a live camera to a file",
       "usage: yelan record [--duration 10s] [--camera SERIAL] OUT.aedat4|OUT.txt|OUT.yelan.h5\n"
       "Records the first attached DAVIS346/DVXplorer (or the one with SERIAL) until --duration has\n"
       "passed (10s, 500ms, 2m; default: until Ctrl-C). Ctrl-C stops cleanly; the file is\n"
       "written atomically and keeps every event decoded before an unplug (exit 1 then).\n",
       cmd_record, "the libusb driver (issue 5)"},
      {"devices", "list attached event cameras",
       "usage: yelan devices\n"
       "Lists attached DAVIS346/DVXplorer cameras: model, USB bus, address, serial.\n",
       cmd_devices, "the libusb driver (issue 5)"},
      {"bench", "benchmarks: kernels, events, networks, sim, run, early-exit, rate-sweep, crop, train",
       "usage: yelan bench kernels [--quick] [--json] [--isa-list avx2,avx512] [--threads-list 1,2]\n"
       "                          [--reps N] [--only NAME] [--chart FILE.svg] [--from RESULTS.json]\n"
       "       yelan bench events [--json]\n"
       "       yelan bench networks [--configs paper,small,tiny] [--threads-list 1,2] [--window W] [--json]\n"
       "       yelan bench sim [--duration 2] [--threads-list 1,2] [--character ben] [--motion 05_04] [--json]\n"
       "       yelan bench run [--configs small,paper] [--threads-list 1,2] [--rate 50] [--beta B] [--weights W1,W2]\n"
       "                       [--crop-margin PX] [--no-torch] [--json]\n"
       "       yelan bench early-exit --weights W [--values 0.5,...,0.99,1.01] [--scenes 12] [--seed 1] [--chart F.svg] [--json]\n"
       "       yelan bench rate-sweep --weights W [--values 20,50,100,150,200] [--scenes 12] [--seed 1] [--chart F.svg] [--json]\n"
       "       yelan bench crop --weights W [--values 0,4,8,16,32] [--scenes 12] [--seed 1] [--beta B] [--chart F.svg] [--json]\n"
       "       yelan bench train [--config small] [--stage pose|mask|both] [--batch 1] [--batches 4] [--steps 20]\n"
       "                         [--threads-list 1] [--sim train] [--json] [--no-torch] [--keep-data FILE.h5]\n"
       "\n"
       "kernels: every convolution shape of the networks (forward, backward-data,\n"
       "backward-weights) per ISA and thread count, with GFLOP/s and % of the FMA peak\n"
       "measured in the same run; memory-bound kernels (BN+ReLU, pooling, LSTM update,\n"
       "softmax) against a memcpy of the same bytes; oneDNN and PyTorch 1.13 on the same\n"
       "shapes when installed (scripts/setup-debian --reference).\n"
       "--quick: the 3x3/1 shapes, best ISA, 1 thread. --only NAME: shapes whose name\n"
       "contains NAME ('memory', 'convlstm.step' for those groups). --from: re-print the\n"
       "table (and --chart) of a saved --json run without measuring.\n"
       "sim: simulated seconds per wall second for each lighting x background, the shares\n"
       "of rendering and the pixel model, and events/s against the real DAVIS346 recording.\n"
       "run: the streaming pipeline per config and thread count: poses/s, per-tick p50/p99 split\n"
       "by stage (TORE, stage 1, stage 2) and the share of ticks that ran stage 1; at each model's\n"
       "own run.beta (its shipped setting; 0.99 without one) unless --beta is given.\n"
       "early-exit, rate-sweep: the pipeline scored on test-split scenes (simulated once, in memory)\n"
       "while beta or the pose rate varies: MPJPE (paper protocol and with the depth prior), the share\n"
       "of ticks that ran stage 1, ms per tick by stage; --chart writes the SVG (and PNG).\n"
       "crop: the same, while the margin (input pixels) of stage 2's crop around the mask varies\n"
       "(0: the whole frame), with the share of the frame the ResNet head ran on.\n"
       "train: the trainer's step (zero_grad, forward, loss, backward, Adam) in samples/s on batches\n"
       "built as yelan train builds them, against PyTorch 1.13 training the same config from the same\n"
       "initial weights on the same batches (ratio ours/torch; the initial losses of both show it).\n",
       cmd_bench, ""},
      {"model", "network summaries and forward passes",
       "usage: yelan model summary --config NAME|FILE [--json]\n"
       "       yelan model forward --weights W --input IN.h5 --output OUT.h5\n"
       "\n"
       "summary: every convolution of both networks as inference runs it (BN and ReLU folded\n"
       "in): state_dict name, op, input and output shapes, parameters, FLOPs and activation\n"
       "memory per frame; parameters per top-level module; totals and the peak memory of one\n"
       "frame's forward (--json: params_mask, params_pose, flops_per_pose, flops_per_mask,\n"
       "activation_bytes_*, peak_bytes_inference, layers, modules).\n"
       "forward: both networks in inference mode on dataset `input` (S x C x H x W, S a\n"
       "multiple of the window); writes masks, scores, heatmaps/stage<i>/{xy,zy,xz} and\n"
       "joints_norm, as weights_tools/make_parity_case.py does for PyTorch.\n",
       cmd_model, ""},
      {"weights", "inspect, compare, verify and initialise HDF5 weights",
       "usage: yelan weights inspect FILE [--json]\n"
       "       yelan weights diff A B [--tol 0] [--all]\n"
       "       yelan weights verify FILE --config NAME|FILE\n"
       "       yelan weights init --config NAME|FILE --seed N -o W.h5\n"
       "       yelan weights combine --mask A.h5 --pose B.h5 -o OUT.h5 [--config NAME|FILE]\n"
       "       yelan weights calibrate --weights W --data DIR -o OUT.h5 [--seconds 3] [--skip 0.5] [--rate 50]\n"
       "                 [--beta B | --choose-beta [--beta-tolerance 0.02]]\n"
       "\n"
       "calibrate: runs the deployed pipeline over DIR/val (or DIR) recordings, with a dancer and\n"
       "empty, fits P(person) = sigmoid(a ln(s + 0.001) + b) on the mask's share s of the frame\n"
       "(both classes weighted equally), prints hit and false-alarm rates and a reliability table\n"
       "before and after, and writes W with the fit in its config (run.presence; --beta: run.beta).\n"
       "--choose-beta: runs the recordings with a dancer once per beta in 0.5..1.01, compares the\n"
       "mask in use at each tick with the true mask, and stores the beta that runs stage 1 least\n"
       "with a mask IoU within --beta-tolerance of the best.\n"
       "\n"
       "Our weights file: HDF5, root attributes format=\"yelan-weights\", version=1, config (JSON);\n"
       "groups mask/ and pose/ with one float32 dataset per PyTorch state_dict key\n"
       "(weights_tools/README.md; weights_tools/export_h5.py converts checkpoints).\n"
       "inspect: format, version, config, tensors and parameters per group, every name and shape.\n"
       "diff: max |a-b| of each tensor above --tol (--all: of every tensor), tensors only in A\n"
       "or B, shape changes; exit 1 when anything differs beyond --tol.\n"
       "verify: every tensor a config needs, with its shape, and nothing else (the config's\n"
       "manifest: weights_tools/configs/NAME.manifest.json, or FILE.manifest.json beside a\n"
       "config FILE). Bad or mismatched files exit 2, one line per problem.\n"
       "combine: the mask group of A and the pose group of B (stages trained apart) in one file;\n"
       "--config: the file's config instead of B's (inference settings such as pose.crop_margin;\n"
       "the tensors must fit it).\n",
       cmd_weights, "HDF5 weights (issue 4)"},
  };
  return table;
}

}  // namespace yelan::cli
