"""What the corpus benches share (bench/corpus_table.py, pilot_estimates.py, pilot_vs_first.py,
combine_offline.py): their common arguments, the scenes of one half of the corpus that
tools/make_corpus.py wrote, and where each scene's reference and its own error lie
(tools/corpus_references.py)."""
import json
import math
import os


def add_corpus_arguments(parser, half, seeds, farm=True):
    """CORPUS and OUT, --half, --seeds and --only; with farm, also --size, --farm and
    --table-only, for the benches that render."""
    parser.add_argument("corpus")
    parser.add_argument("out")
    parser.add_argument("--half", default=half, choices=["measure", "tune", "all"])
    parser.add_argument("--seeds", type=int, nargs="+", default=seeds)
    parser.add_argument("--only", default="", help="comma-separated scene names")
    if farm:
        parser.add_argument("--size", type=int, default=64)
        parser.add_argument("--farm", default="build/bin/farm")
        parser.add_argument("--table-only", action="store_true",
                            help="render nothing, tabulate OUT")


def reference_seeds(reference_json):
    """The seeds tools/corpus_references.py rendered a reference from: its list, or 1..seeds in
    references made before it wrote one."""
    with open(reference_json) as f:
        r = json.load(f)
    return set(r.get("seed_list", range(1, int(r["seeds"]) + 1)))


def corpus_scenes(args):
    """The corpus.json entries of args.half, narrowed to args.only when given. Refuses seeds a
    scene's reference was rendered with: a render of seed k and the reference's render of seed k
    draw the same random numbers (sample k of seed s is stream (s, k) whatever the budget), so
    their errors cancel in part, and the render's relative MSE against the reference comes out
    low by the share they have in common (bdpt's by 1.6x on environment-1 at 10 s, docs/corpus.md,
    "Seeds shared with the references")."""
    with open(os.path.join(args.corpus, "corpus.json")) as f:
        scenes = [s for s in json.load(f)["scenes"] if args.half in ("all", s["half"])]
    only = set(filter(None, args.only.split(",")))
    scenes = [s for s in scenes if not only or s["name"] in only]
    for s in scenes:
        path = os.path.join(os.path.dirname(os.path.join(args.corpus, s["scene"])),
                            "reference.json")
        if not os.path.exists(path):
            continue
        shared = sorted(set(getattr(args, "seeds", [])) & reference_seeds(path))
        if shared:
            raise SystemExit(f"{s['name']}: seeds {shared} are the reference's own ({path}); "
                             "a render of one shares its random numbers and looks better than "
                             "it is: use others (the benches' default is 101 up)")
    return scenes


def scene_path(args, s):
    return os.path.join(args.corpus, s["scene"])


def reference_path(args, s):
    return os.path.join(os.path.dirname(scene_path(args, s)), "reference.exr")


def reference_floor(args, s):
    """The reference's own relative MSE (reference.json): each bench takes it off a render's
    measured error, which is about the sum of the two, independent as they are."""
    with open(os.path.join(os.path.dirname(scene_path(args, s)), "reference.json")) as f:
        return json.load(f)["reference_relmse"]


def geometric_mean(xs):
    """The geometric mean of positive numbers (of ratios of errors, in the benches' tables)."""
    return math.exp(sum(math.log(x) for x in xs) / len(xs))


def write_table(args, name, lines):
    """Writes the table's lines to OUT/name and prints them."""
    table = "\n".join(lines) + "\n"
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, name), "w") as f:
        f.write(table)
    print(table)
