"""Reads a conformance report as a CI server or a browser would and prints what it found, one
fact a line, for test_cf_report.c to compare: `junit FILE` (xml.etree: the counts, each suite's
properties, each case's classname, name and failure or skip message), `html FILE` (xml.etree,
so the file is well-formed; html.parser as a browser's reading; the DUT table, the summary, each
case section and its telegram rows; "self-contained" when nothing refers out of the file)."""
import html.parser
import sys
import xml.etree.ElementTree as ET


def junit(path):
    root = ET.parse(path).getroot()
    print(f"testsuites tests={root.get('tests')} failures={root.get('failures')} "
          f"skipped={root.get('skipped')}")
    for suite in root.findall("testsuite"):
        props = {p.get("name"): p.get("value") for p in suite.find("properties")}
        print(f"suite {suite.get('name')} tests={suite.get('tests')} "
              f"failures={suite.get('failures')} skipped={suite.get('skipped')} "
              f"rate={props['rate']} vendor={props['vendor']}")
        for case in suite.findall("testcase"):
            verdict = "pass"
            failure, skipped = case.find("failure"), case.find("skipped")
            if failure is not None:
                assert failure.text == failure.get("message")
                verdict = "failure: " + failure.get("message")
            elif skipped is not None:
                verdict = "skipped: " + skipped.get("message")
            assert case.find("system-out") is not None
            print(f"  case {case.get('classname')} {case.get('name')} {verdict}")


def text(e):
    return "".join(e.itertext())


def rows(table):
    return [[text(c) for c in tr] for tr in table.findall("tr")]


def html_cases(body):
    for e in body:
        if e.tag == "h2" and text(e).startswith("Cases"):
            print("h2", text(e))
        if e.tag != "div" or e.get("class") != "case":
            continue
        verdict = e.find("h3/span").get("class").split()[1]
        facts = dict(rows(e.find("table[@class='case-facts']")))
        line = f"case {e.get('id')} {verdict} {facts['Group']}"
        if "Reason" in facts:
            line += " reason=" + facts["Reason"]
        print(line)
        tg = e.find("table[@class='telegrams']")
        for r in rows(tg)[1:] if tg is not None else []:
            print("  tg " + "|".join(r))


class Outward(html.parser.HTMLParser):
    """Counts what a browser would fetch or run: scripts, src, links out of the file."""

    def __init__(self):
        super().__init__()
        self.outward = 0

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag in ("script", "link", "img", "iframe", "object") or "src" in a:
            self.outward += 1
        if "href" in a and not a["href"].startswith("#"):
            self.outward += 1


def html_report(path):
    root = ET.parse(path).getroot()
    body = root.find("body")
    print("title", text(root.find("head/title")))
    dut = rows(body.find("table[@class='dut']"))
    keep = ("Vendor", "Model", "Ident number", "GSD file", "Address", "Medium", "Rates",
            "Date", "Tool")
    print("dut " + " ".join(f"{k}={v}" for k, v in dut if k in keep))
    for r in rows(body.find("table[@class='summary']")):
        print("summary " + " | ".join(r))
    html_cases(body)
    with open(path, encoding="utf-8") as f:
        p = Outward()
        p.feed(f.read())
    anchors = {e.get("id") for e in root.iter() if e.get("id")}
    links = [a.get("href")[1:] for a in root.iter("a")]
    if p.outward == 0 and all(link in anchors for link in links) and links:
        print("self-contained")


if __name__ == "__main__":
    {"junit": junit, "html": html_report}[sys.argv[1]](sys.argv[2])
