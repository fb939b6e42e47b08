"""The reference of the user guide covers every study-file key and every command-line option,
and documents none that does not exist.

The truth comes from uq-driver itself, not from its sources: every table of a study file refuses
an unknown key and names the keys it takes (`unknown field `zzz`, expected one of ...`), every
enumeration names its values (`unknown variant ...`), and `--help` lists each command's options.
The guide's side: docs/src/reference/study-file.md marks each table of keys with
`<!-- keys: CONTEXT ... -->`, docs/src/reference/commands.md each table of options with
`<!-- options: COMMAND -->`."""
import pathlib
import re
import subprocess

import pytest

from conftest import DRIVER, ROOT

STUDY_FILE_MD = ROOT / "docs" / "src" / "reference" / "study-file.md"
COMMANDS_MD = ROOT / "docs" / "src" / "reference" / "commands.md"
HEAD = 'name = "probe"\nfmu = "Probe.fmu"\n'


def driver() -> str:
    if not DRIVER.is_file():
        pytest.fail(f"{DRIVER} is missing: run `make build` first")
    return str(DRIVER)


def error_of(study: str, tmp: pathlib.Path) -> str:
    path = tmp / "probe.toml"
    path.write_text(study)
    r = subprocess.run([driver(), "run", str(path), "--out", str(tmp / "out")],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode != 0, f"the probe study was accepted:\n{study}"
    return r.stderr


def names_offered(stderr: str, what: str) -> list:
    """The names an 'unknown field' / 'unknown variant' error offers."""
    m = re.search(rf"unknown {what} `zzz`, (expected [^\n]*|there are no fields)", stderr)
    assert m, f"no 'unknown {what}' error in: {stderr}"
    return re.findall(r"`([^`]+)`", m.group(1))


def keys(body: str, tmp) -> set:
    return set(names_offered(error_of(HEAD + body + "\nzzz = 1\n", tmp), "field"))


def variants(body: str, tmp) -> list:
    return names_offered(error_of(HEAD + body.replace("VALUE", '"zzz"') + "\n", tmp), "variant")


def probed_keys(tmp) -> dict:
    """Every table of a study file and the keys uq-driver says it takes."""
    ctx = {
        "top": keys("", tmp),
        "experiment": keys("[experiment]", tmp),
        "outputs": keys("[outputs]", tmp),
        "inputs": keys("[inputs]", tmp),
        "analysis": keys("[analysis]", tmp),
        "correlation": keys("[[correlation]]", tmp),
        "paper": keys("[[paper]]", tmp),
        "variants": keys("[[variants]]", tmp),
        "system": keys("[system]", tmp),
        "system.dependence": keys("[[system.dependence]]", tmp),
    }
    for kind in variants("[method]\nkind = VALUE", tmp):
        ctx[f"method.{kind}"] = keys(f'[method]\nkind = "{kind}"', tmp)
    for dist in variants('[[parameters]]\nname = "K"\ndistribution = VALUE', tmp):
        ctx[f"parameters.{dist}"] = keys(f'[[parameters]]\nname = "K"\ndistribution = "{dist}"', tmp)
    for kind in variants("[[qoi]]\nkind = VALUE", tmp):
        ctx[f"qoi.{kind}"] = keys(f'[[qoi]]\nkind = "{kind}"', tmp)
    return ctx


def marked(path, marker):
    """Each `<!-- MARKER: WHAT -->` of the Markdown file `path`: (WHAT, the lines after it)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    for i, line in enumerate(lines):
        m = re.match(rf"<!-- {marker}: (.+?) -->", line)
        if m:
            yield m.group(1), lines[i + 1:]


def documented_keys() -> dict:
    """`<!-- keys: A B -->` followed by a table whose first column holds `key`: each context
    A, B documents those keys (a marker without a table documents none)."""
    doc = {}
    for contexts, after in marked(STUDY_FILE_MD, "keys"):
        found = set()
        for row in after:
            if row.startswith("|"):
                cell = row.split("|")[1].strip()
                km = re.fullmatch(r"`([A-Za-z0-9_]+)`", cell)
                if km:
                    found.add(km.group(1))
            elif found or (row.strip() and not row.startswith("|")):
                break
        for c in contexts.split():
            assert c not in doc, f"context {c} is marked twice"
            doc[c] = found
    return doc


def mismatches(actual: dict, doc: dict, label: str, page: str, unknown: str) -> list:
    """What the documented sets `doc` miss or add against the `actual` ones (by context, in the
    order of `actual`), each context named by `label` (a format string), their tables being in
    `page` and an entry documented but not there called `unknown`."""
    problems = []
    for c, have in actual.items():
        name = label.format(c)
        if c not in doc:
            problems.append(f"{name}: no table in {page} {sorted(have)})")
            continue
        if have - doc[c]:
            problems.append(f"{name}: undocumented {sorted(have - doc[c])}")
        if doc[c] - have:
            problems.append(f"{name}: documented but {unknown} {sorted(doc[c] - have)}")
    return problems


def test_the_reference_documents_every_study_file_key_and_no_unknown_one(tmp_path):
    probed = dict(sorted(probed_keys(tmp_path).items()))
    doc = documented_keys()
    problems = mismatches(probed, doc, "{}", "study-file.md (keys", "unknown to uq-driver")
    # Contexts the probes cannot list (the keys every parameter takes whatever its family) are
    # checked by acceptance below; any other documented context must exist.
    for c in sorted(set(doc) - set(probed) - {"parameters"}):
        problems.append(f"{c}: documented, but uq-driver has no such table or kind")
    assert not problems, "\n".join(problems)
    assert len(probed) >= 35, sorted(probed)


def test_the_keys_every_parameter_takes_are_accepted_and_a_wrong_one_refused(tmp_path):
    common = documented_keys()["parameters"]
    assert common == {"name", "distribution", "level", "allow_negative"}
    body = ('[[parameters]]\nname = "K"\ndistribution = "normal"\nlevel = "inner"\n'
            'allow_negative = true\nmean = 1.0\nstd = 0.1\n')
    err = error_of(HEAD + body, tmp_path)  # refused later (no experiment, no FMU), not for a key
    assert "unknown field" not in err and "level" not in err and "allow_negative" not in err, err
    err = error_of(HEAD + body + "levle = 1\n", tmp_path)
    assert "unknown field `levle`" in err, err


def test_every_value_of_every_enumerated_key_is_documented(tmp_path):
    text = STUDY_FILE_MD.read_text(encoding="utf-8")
    probes = {
        "method kind": "[method]\nkind = VALUE",
        "distribution": '[[parameters]]\nname = "K"\ndistribution = VALUE',
        "qoi kind": "[[qoi]]\nkind = VALUE",
        "chaos": '[method]\nkind = "scm"\nnodes = 2\nchaos = VALUE',
        "sparse-grid rule": '[method]\nkind = "sparse_grid"\nlevel = 1\nrule = VALUE',
        "regression design": '[method]\nkind = "pce_regression"\norder = 2\ndesign = VALUE',
        "Sobol' base": '[method]\nkind = "sobol_sampling"\nsamples = 4\nbase = VALUE',
        "Sperling window": '[[qoi]]\nkind = "sperling"\nname = "W"\nsignal = "a"\nwindow = VALUE',
        "Sperling direction": '[[qoi]]\nkind = "sperling"\nname = "W"\nsignal = "a"\ndirection = VALUE',
        "Sperling statistic": '[[qoi]]\nkind = "sperling"\nname = "W"\nsignal = "a"\nstatistic = VALUE',
    }
    missing = []
    for what, body in probes.items():
        for v in variants(body, tmp_path):
            if f"`{v}`" not in text and f'"{v}"' not in text:
                missing.append(f"{what} {v}")
    assert not missing, f"values not in study-file.md: {missing}"


def help_of(*args) -> str:
    r = subprocess.run([driver(), *args, "--help"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    return r.stdout


def subcommands(*path) -> list:
    text = help_of(*path)
    section = text.split("Commands:")[1].split("Options:")[0]
    names = [m.group(1) for m in re.finditer(r"^  (\S+)\s", section, re.M)]
    return [n for n in names if n != "help"]


def options_of(*path) -> set:
    section = help_of(*path).split("Options:")[1]
    opts = set(re.findall(r"^\s+(?:-\w, )?(--[a-z][a-z0-9-]*)", section, re.M))
    return opts - {"--help", "--version"}


def documented_options() -> dict:
    doc = {}
    for command, after in marked(COMMANDS_MD, "options"):
        found = set()
        for row in after:
            if not row.startswith("|"):
                break
            found |= set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", row.split("|")[1]))
        assert command not in doc, f"{command} is marked twice"
        doc[command] = found
    return doc


def all_commands() -> list:
    out = []
    for c in subcommands():
        try:
            subs = subcommands(c)
        except (IndexError, AssertionError):
            subs = []
        out += [f"{c} {s}" for s in subs] if subs else [c]
    return out


def test_the_reference_documents_every_command_and_option_and_no_unknown_one():
    doc = documented_options()
    commands = all_commands()
    options = {c: options_of(*c.split()) for c in commands}
    problems = mismatches(options, doc, "uq-driver {}", "commands.md (options", "unknown")
    for c in sorted(set(doc) - set(commands)):
        problems.append(f"uq-driver {c}: documented, but there is no such command")
    assert not problems, "\n".join(problems)
    assert "run" in commands and "surrogate eval" in commands, commands
