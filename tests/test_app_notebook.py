"""The design page in a real Jupyter kernel (docs/app.md, "In Jupyter"): a notebook
written with nbformat and run by nbclient in an ipykernel of this interpreter.

No browser runs here, so the test stands in for the notebook's side of Panel's comms,
as Panel's JupyterLab extension does it: it opens the page's comm, receives the
Bokeh patches the page sends when a view is redrawn, and sends a control's change
back as a patch."""

from __future__ import annotations

import asyncio
import json
import re
import sys
import uuid
from concurrent.futures import ThreadPoolExecutor

import nbformat
import numpy as np
from jupyter_client.kernelspec import KernelSpecManager
from jupyter_client.manager import AsyncKernelManager
from nbclient import NotebookClient

import boringbar as bb

#: Panel's notebook output (a page and the id of its root model) and the bundle
#: pn.extension() displays first (BokehJS and Panel's JavaScript)
EXEC_MIME = "application/vnd.holoviews_exec.v0+json"
LOAD_MIME = "application/vnd.holoviews_load.v0+json"

SETUP = """\
import asyncio
import sys
import warnings

import panel as pn

import boringbar as bb

for category in (DeprecationWarning, PendingDeprecationWarning):
    warnings.filterwarnings("error", category=category, module="boringbar.app")
print(sys.executable)
print(bb.__file__)"""

SHOW = "page = bb.design_page()\npage"

FIND = '''\
def part(css):
    """A widget or pane of the page by its CSS class (as the browser test finds it)."""
    return next(o for o in page.select() if css in (getattr(o, "css_classes", None) or []))


status = part("status-run")
aux = next(m for p in page.select(pn.pane.Bokeh) for m in p.object.select({"name": "run-aux"}))


async def drawn(change):
    """Wait for the run view's status to name ``change`` (the page shows it after the
    view's data), then print the ball's reach (mm): its largest distance from the
    cavity's centre."""
    for _ in range(600):
        if f"change {change}: drawn" in status.object:
            print(float(max(map(abs, aux.data["y"]))))
            return
        await asyncio.sleep(0.1)
    raise TimeoutError(status.object)


await drawn(0)'''

#: the cells, in order; the test sends a gap of 0.35 mm through the comm before the last
CELLS = (SETUP, SHOW, FIND,
         'part("ctl-ball-gap_mm").value = 0.2\nawait drawn(1)',
         'await drawn(2)\nprint(part("ctl-ball-gap_mm").value)')


class Frontend:
    """The notebook's side of the page shown by ``html`` (a cell's output): the page's
    models by id, and its comms once :meth:`open`."""

    def __init__(self, client: NotebookClient, html: str):
        self.client, self.received, self.comm = client, [], uuid.uuid4().hex
        self.ids = dict(re.findall(r'"(client_comm_id|comm_id)":"(\w+)"', html))
        docs = json.loads(re.search(r"var docs_json = (\{.*?\});\n", html).group(1))
        self.models = list(_models(docs))

    def model(self, key: str, value: str) -> str:
        """The id of the model whose attribute ``key`` is or holds ``value``."""
        return next(m["id"] for m in self.models
                    if value == (a := m.get("attributes", {}).get(key))
                    or isinstance(a, list) and value in a)

    async def open(self) -> None:
        """Open the page's client comm; the kernel answers by opening the comm its
        patches come on, whose messages nbclient then hands to :meth:`handle_msg`."""
        self._send("comm_open", target_name=self.ids["client_comm_id"], data={})
        while True:
            msg = await self.client.kc.iopub_channel.get_msg(timeout=60)
            content = msg["content"]
            if msg["msg_type"] == "comm_open" and content["target_name"] == self.ids["comm_id"]:
                self.client.comm_objects[content["comm_id"]] = self
                return

    def handle_msg(self, msg: dict) -> None:
        self.received.append(msg)

    def set_value(self, model_id: str, value) -> None:
        """A widget's new value, sent as the browser sends it: a Bokeh patch."""
        event = {"kind": "ModelChanged", "model": {"id": model_id}, "attr": "value",
                 "new": value}
        self._send("comm_msg", data={"header": {"msgid": uuid.uuid4().hex,
                                                "msgtype": "PATCH-DOC"},
                                     "metadata": {}, "content": {"events": [event]}})

    def _send(self, msg_type: str, **content) -> None:
        kc = self.client.kc
        kc.shell_channel.send(kc.session.msg(msg_type, {"comm_id": self.comm, **content}))

    def columns(self, model_id: str) -> list[dict]:
        """Each new data of source ``model_id`` the page sent, as arrays."""
        events, buffers = _patches(self.received)
        return [{k: _array(v, buffers) for k, v in (e.get("data") or e["new"])["entries"]}
                for e in events if e["model"]["id"] == model_id and e.get("attr") == "data"]


def _models(node):
    """Every Bokeh model serialised in ``node`` (a document's JSON)."""
    if isinstance(node, dict):
        if node.get("type") == "object" and "id" in node:
            yield node
        for v in node.values():
            yield from _models(v)
    elif isinstance(node, list):
        for v in node:
            yield from _models(v)


def _patches(messages) -> tuple[list, dict]:
    """The events and buffers of the Bokeh patches in ``messages``: Panel sends each
    patch's header, metadata and content, then each buffer's reference and the buffer."""
    events, buffers, ref = [], {}, None
    for m in messages:
        data = m["content"]["data"]
        if m.get("buffers"):
            buffers[ref] = bytes(m["buffers"][0])
        elif isinstance(data, str):
            part = json.loads(data)
            events += part.get("events", [])
            ref = part.get("id", ref)
    return events, buffers


def _array(value, buffers) -> np.ndarray:
    if isinstance(value, dict) and value.get("type") == "ndarray":
        order = "<" if value["order"] == "little" else ">"
        raw = buffers[value["array"]["data"]["id"]]
        return np.frombuffer(raw, dtype=np.dtype(value["dtype"]).newbyteorder(order))
    return np.asarray(value)


async def _run(client: NotebookClient, nb) -> Frontend:
    """Run the cells as a notebook would: the page's comms opened once it is shown, a
    gap of 0.35 mm sent through them before the last cell.  The frontend keeps what
    the page sent while the fourth cell changed the gap."""
    setup, show, first, moved, sent = nb.cells
    async with client.async_setup_kernel(cleanup_kc=True):
        await client.async_execute_cell(setup, 0)
        await client.async_execute_cell(show, 1)
        frontend = Frontend(client, _result(show).data["text/html"])
        await frontend.open()
        await client.async_execute_cell(first, 2)
        frontend.received.clear()  # keep only what the gap change sends
        await client.async_execute_cell(moved, 3)
        frontend.set_value(frontend.model("css_classes", "ctl-ball-gap_mm"), 0.35)
        await client.async_execute_cell(sent, 4)
    return frontend


def _result(cell):
    return next(o for o in cell.outputs if o.output_type == "execute_result")


def _printed(cell) -> list[str]:
    """The lines ``cell`` printed."""
    return "".join(o.text for o in cell.outputs if o.output_type == "stream"
                   and o.name == "stdout").splitlines()


def test_the_page_runs_in_a_jupyter_kernel(tmp_path):
    path = tmp_path / "design_page.ipynb"
    nbformat.write(nbformat.v4.new_notebook(
        cells=[nbformat.v4.new_code_cell(c) for c in CELLS]), path)
    nb = nbformat.read(path, as_version=4)
    # only ipykernel's own kernel, which runs this interpreter (not one registered in
    # the user's Jupyter folders under the same name)
    km = AsyncKernelManager(kernel_name="python3",
                            kernel_spec_manager=KernelSpecManager(kernel_dirs=[]))
    client = NotebookClient(nb, km=km, timeout=300, store_widget_state=False,
                            resources={"metadata": {"path": str(tmp_path)}})
    # a thread of its own: a test before may have left an event loop running in this one
    with ThreadPoolExecutor(max_workers=1) as runner:
        frontend = runner.submit(asyncio.run, _run(client, nb)).result()
    nbformat.write(nb, tmp_path / "executed.ipynb")
    outputs = [o for cell in nb.cells for o in cell.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    assert not [o.text for o in outputs if o.output_type == "stream" and "Traceback" in o.text]

    setup, show, first, moved, sent = nb.cells
    assert _printed(setup) == [sys.executable, bb.__file__]  # this interpreter, this package
    # pn.extension()'s scripts, then the page as Panel shows it in a notebook
    assert any(LOAD_MIME in o.get("data", {}) for o in show.outputs)
    result = _result(show)
    root = result.metadata[EXEC_MIME]["id"]
    assert EXEC_MIME in result.data and f"data-root-id=\"{root}\"" in result.data["text/html"]
    assert frontend.model("name", "run-aux")  # the run figure is in the page's document

    # the ball's reach follows the walls: half of each gap (0.5, 0.2, 0.35 mm)
    reach = [float(_printed(c)[0]) for c in (first, moved, sent)]
    assert 0.24 < reach[0] <= 0.25 and 0.09 < reach[1] <= 0.1 and 0.17 < reach[2] <= 0.175
    assert float(_printed(sent)[1]) == 0.35  # the change sent through the comm arrived
    # the redraw after the kernel's change reached the notebook through the comm
    drawings = frontend.columns(frontend.model("name", "run-aux"))
    assert drawings, "the run view's redraw did not come through the comm"
    assert float(np.abs(drawings[-1]["y"]).max()) == reach[1]
