"""A TOML file saved with a byte-order mark, and a path given as bytes (correction/io/tomlfile.py).

Windows editors (Notepad before 2019, Excel's "CSV UTF-8", PowerShell's ``Out-File``) write a
UTF-8 byte-order mark, ``EF BB BF``, before the text; TOML forbids none of it but tomllib reads
it as a stray character. Expected: the mark is skipped and the file reads as the same file
without it; a UTF-16 or UTF-32 mark (the encodings ``Out-File`` and Notepad's "Unicode" save in)
is refused in one sentence naming the encoding and the fix. A path reads the same as ``str``,
``bytes`` (``os.fsencode``) and ``pathlib.Path``; anything else is one sentence naming ``what``.
"""

from __future__ import annotations

import codecs
import os
import pathlib

import pytest

from rigsim.correction.io.tomlfile import path_text, read_toml

TEXT = '[transfer_function]\nnum = [1.0]\nden = [0.001, 1.0]\nname = "Zylinder \u00e4"\n'


def test_a_utf8_byte_order_mark_is_read_as_utf8(tmp_path):
    plain, marked = tmp_path / "plain.toml", tmp_path / "marked.toml"
    plain.write_text(TEXT, encoding="utf-8")
    marked.write_bytes(codecs.BOM_UTF8 + TEXT.encode("utf-8"))
    assert read_toml(marked, "actuator file") == read_toml(plain, "actuator file")
    assert read_toml(marked, "actuator file")["transfer_function"]["name"] == "Zylinder \u00e4"


@pytest.mark.parametrize(("encoding", "name"), [("utf-16", "UTF-16"), ("utf-16-be", "UTF-16"),
                                                ("utf-32", "UTF-32"), ("utf-32-be", "UTF-32")])
def test_a_utf16_or_utf32_byte_order_mark_is_named(tmp_path, encoding, name):
    path = tmp_path / "wide.toml"
    bom = {"utf-16-be": codecs.BOM_UTF16_BE, "utf-32-be": codecs.BOM_UTF32_BE}.get(encoding, b"")
    path.write_bytes(bom + TEXT.encode(encoding))
    with pytest.raises(ValueError) as err:
        read_toml(path, "actuator file")
    assert str(err.value) == f"actuator file {str(path)!r} is {name} (its byte-order mark says so), not UTF-8; save it as UTF-8"


def test_a_path_as_str_bytes_or_pathlike(tmp_path):
    path = tmp_path / "a.toml"
    path.write_text(TEXT, encoding="utf-8")
    want = read_toml(str(path), "actuator file")
    assert read_toml(os.fsencode(path), "actuator file") == want == read_toml(pathlib.Path(path), "actuator file")
    assert path_text(os.fsencode(path), "path") == str(path)


@pytest.mark.parametrize(("value", "said"), [(None, "got NoneType"), (3, "got int"), (["a.toml"], "got list"),
                                              ("", "'' names no file"), (b"", "'' names no file")])
def test_anything_else_is_one_sentence_naming_what(value, said):
    with pytest.raises(ValueError) as err:
        read_toml(value, "grid file")
    assert str(err.value).startswith("grid file ") and said in str(err.value) and "\n" not in str(err.value)
