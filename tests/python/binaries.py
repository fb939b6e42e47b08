"""Just enough ELF and PE reading for the checks on the packaged binaries: section names, the
glibc versions an ELF shared object needs, a DLL's exports and imported DLLs. Written from the
ELF (System V gABI) and PE/COFF specifications, independently of the packaging code."""
import struct


# ---------------------------------------------------------------- ELF (64-bit, little endian)

def _elf_sections(data):
    assert data[:4] == b"\x7fELF" and data[4] == 2 and data[5] == 1, "not an ELF64 LE file"
    shoff, = struct.unpack_from("<Q", data, 0x28)
    shentsize, shnum, shstrndx = struct.unpack_from("<HHH", data, 0x3A)
    sections = []
    for i in range(shnum):
        name, stype, _flags, _addr, offset, size, link = struct.unpack_from(
            "<IIQQQQI", data, shoff + i * shentsize)
        sections.append({"name": name, "type": stype, "offset": offset, "size": size,
                         "link": link})
    strtab = sections[shstrndx]
    for s in sections:
        s["name"] = _cstr(data, strtab["offset"] + s["name"])
    return sections


def _cstr(data, at):
    return data[at:data.index(b"\0", at)].decode()


def elf_section_names(data):
    return [s["name"] for s in _elf_sections(data)]


def elf_needed_versions(data):
    """{library: [version names]} from .gnu.version_r (SHT_GNU_verneed)."""
    sections = _elf_sections(data)
    out = {}
    for s in sections:
        if s["type"] != 0x6FFFFFFE:
            continue
        strings = sections[s["link"]]["offset"]
        at = s["offset"]
        while True:
            _ver, cnt, file_, aux, nxt = struct.unpack_from("<HHIII", data, at)
            names = []
            a = at + aux
            for _ in range(cnt):
                _hash, _flags, _other, name, anext = struct.unpack_from("<IHHII", data, a)
                names.append(_cstr(data, strings + name))
                a += anext
            out[_cstr(data, strings + file_)] = names
            if nxt == 0:
                break
            at += nxt
    return out


def max_glibc(data):
    """The highest GLIBC_x.y version the object needs, as a tuple (e.g. (2, 34))."""
    versions = [tuple(int(p) for p in v[len("GLIBC_"):].split("."))
                for vs in elf_needed_versions(data).values() for v in vs
                if v.startswith("GLIBC_") and v[6:7].isdigit()]
    return max(versions)


# ---------------------------------------------------------------- PE32+ (a 64-bit DLL)

class PE:
    def __init__(self, data):
        assert data[:2] == b"MZ", "not a PE file"
        self.data = data
        pe, = struct.unpack_from("<I", data, 0x3C)
        assert data[pe:pe + 4] == b"PE\0\0"
        coff = pe + 4
        (self.machine, nsec, _time, self.symbol_table, self.symbol_count, opt_size,
         self.characteristics) = struct.unpack_from("<HHIIIHH", data, coff)
        opt = coff + 20
        assert struct.unpack_from("<H", data, opt)[0] == 0x20B, "not PE32+"
        ndirs, = struct.unpack_from("<I", data, opt + 108)
        self.dirs = [struct.unpack_from("<II", data, opt + 112 + 8 * i) for i in range(ndirs)]
        self.sections = []
        for i in range(nsec):
            at = opt + opt_size + 40 * i
            name = data[at:at + 8].rstrip(b"\0").decode()
            vsize, vaddr, rsize, rptr = struct.unpack_from("<IIII", data, at + 8)
            self.sections.append((name, vaddr, max(vsize, rsize), rptr))

    def offset(self, rva):
        for _name, vaddr, size, rptr in self.sections:
            if vaddr <= rva < vaddr + size:
                return rva - vaddr + rptr
        raise ValueError(f"RVA {rva:#x} in no section")

    def cstr(self, rva):
        return _cstr(self.data, self.offset(rva))

    def exports(self):
        rva, size = self.dirs[0]
        if size == 0:
            return []
        at = self.offset(rva)
        # Export directory: NumberOfNames at +24, AddressOfNames (RVA of RVAs) at +32.
        nnames, = struct.unpack_from("<I", self.data, at + 24)
        names, = struct.unpack_from("<I", self.data, at + 32)
        return [self.cstr(struct.unpack_from("<I", self.data, self.offset(names) + 4 * i)[0])
                for i in range(nnames)]

    def imported_dlls(self):
        rva, size = self.dirs[1]
        out = []
        at = self.offset(rva)
        while True:
            desc = struct.unpack_from("<IIIII", self.data, at)
            if desc == (0, 0, 0, 0, 0):
                return out
            out.append(self.cstr(desc[3]))
            at += 20
