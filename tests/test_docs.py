"""The README states the architecture the code has: its Layout tree lists exactly the controller's packages and
modules, and its layer table lists the layers in CHAIN_ORDER. The README stays a front door (<= 300 lines, the
rest in docs/), and every relative link of it and of docs/ reaches a file."""

import re
from pathlib import Path

from controller.core.chain import CHAIN_ORDER

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def section(title: str) -> str:
    """The text of the README section `## title` (up to the next `## `)."""
    start = README.index(f"\n## {title}\n")
    end = README.find("\n## ", start + 1)
    return README[start:end if end >= 0 else None]


def controller_tree() -> dict[str, str]:
    """{package: its description} from the Layout tree's controller/ entries (continuation lines included)."""
    block = section("Layout").split("```")[1]
    lines = block.splitlines()
    first = next(i for i, line in enumerate(lines) if line.startswith("controller/"))
    packages, current = {}, None
    for line in lines[first + 1:]:
        m = re.match(r"^  (\w+)/\s+(.*)$", line)
        if m:
            current = m.group(1)
            packages[current] = m.group(2)
        elif line.startswith("   ") and current is not None:
            packages[current] += " " + line.strip()
        else:
            break
    return packages


def test_the_readme_tree_lists_exactly_the_controller_packages():
    packages = sorted(p.name for p in (ROOT / "controller").iterdir() if (p / "__init__.py").exists())
    assert sorted(controller_tree()) == packages


def test_the_readme_tree_names_every_module_of_each_controller_package_but_the_layers():
    missing = {}
    for package, text in controller_tree().items():
        if package == "layers":  # "one file per layer of the table above"
            continue
        names = {p.name for p in (ROOT / "controller" / package).glob("*.py") if p.name != "__init__.py"}
        named = set(re.findall(r"\b(\w+\.py)\b", text))
        if names != named:
            missing[package] = {"not in the README": sorted(names - named), "not in the tree": sorted(named - names)}
    assert missing == {}


def test_the_readme_layer_table_is_in_chain_order_and_names_each_layers_file():
    rows = re.findall(r"^\| (\w+) \| `controller/layers/(\w+)\.py` \|", section("What runs"), flags=re.M)
    assert tuple(name for name, _ in rows) == CHAIN_ORDER
    from controller.system import layer_classes

    assert {name: cls.__module__.rsplit(".", 1)[-1] for name, cls in layer_classes().items()} == dict(rows)


def test_the_readme_chain_line_is_in_chain_order():
    line = next(x for x in section("What runs").splitlines() if x.startswith("plant.read()"))
    assert tuple(line.split(" -> ")[1:-1]) == CHAIN_ORDER


def markdown_pages() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


def relative_links(text: str) -> list[str]:
    """The targets of the Markdown links and images in `text` that are paths (no URL, no bare #anchor), outside
    fenced code blocks, without their #anchor."""
    text = re.sub(r"^```.*?^```", "", text, flags=re.M | re.S)
    targets = re.findall(r"\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)", text)
    return [t.split("#")[0] for t in targets if not re.match(r"^[a-zA-Z][a-zA-Z+.-]*:", t) and not t.startswith("#")]


def test_every_relative_link_in_the_readme_and_docs_reaches_a_file():
    broken = {}
    for page in markdown_pages():
        missing = [t for t in relative_links(page.read_text()) if not (page.parent / t).exists()]
        if missing:
            broken[str(page.relative_to(ROOT))] = missing
    assert broken == {}


def test_the_link_check_sees_links_and_images():
    assert relative_links("[a](x.md#b) ![i](img/p.png) [u](https://e.org) [s](#here)\n```\n[c](no.md)\n```") == [
        "x.md", "img/p.png"]


def test_the_readme_is_a_front_door():
    assert len(README.splitlines()) <= 300  # issue 28: what it is, how to run it, the tables; the rest in docs/
