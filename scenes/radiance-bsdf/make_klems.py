#!/usr/bin/env python3
"""Writes the Klems BSDF files of this folder (LBNL XML, as WINDOW 6 and wrapBSDF write them).

deflect.xml  Klems full basis, IncidentDataStructure Columns. Smooth in the patches' centre
             angles but far from symmetric, so that a wrong side, azimuth sense or up vector
             shows: with (theta_i, phi_i) the incident patch's centre and (theta_o, phi_o) the
             outgoing one's, each in its own hemisphere's angles,
               Transmission Front  a (1 + 0.9 cos(phi_o - phi_i - 90 deg)) (0.5 + cos theta_o)
                                     (1 + 0.7 sin phi_i)
               Transmission Back   b (1 + 0.9 cos(phi_o - phi_i + 45 deg)) (0.5 + cos theta_o)
                                     (1 + 0.7 cos phi_o)
               Reflection Front    0.10 / pi
               Reflection Back     c (1 + 0.5 cos(phi_o - phi_i)) (with a, b, c below).
diffuser.xml Klems quarter basis, IncidentDataStructure Rows: a Lambertian diffuser,
             transmission 0.35 / pi both ways, reflection 0.2 / pi on both sides.
tinted.xml   the diffuser's data as CIE Y, with CIE X = 1.2 Y and CIE Z = 0.6 Y (a warm tint).

Run: python3 make_klems.py (writes both files beside itself).
"""
import math
import os

BASES = {
    "LBNL/Klems Full": ([0, 5, 15, 25, 35, 45, 55, 65, 75, 90], [1, 8, 16, 20, 24, 24, 24, 16, 12]),
    "LBNL/Klems Quarter": ([0, 9, 27, 45, 63, 90], [1, 8, 12, 12, 8]),
}


def patches(name):
    bounds, phis = BASES[name]
    out = []
    for r, n in enumerate(phis):
        lo, hi = bounds[r], bounds[r + 1]
        theta = 0.0 if r == 0 else 0.5 * (lo + hi)
        c0, c1 = math.cos(math.radians(lo)), math.cos(math.radians(hi))
        omega = math.pi * (c0 * c0 - c1 * c1) / n
        for k in range(n):
            out.append((math.radians(theta), 2 * math.pi * k / n, omega))
    return out


def basis_xml(name):
    bounds, phis = BASES[name]
    blocks = []
    for r, n in enumerate(phis):
        centre = 0 if r == 0 else 0.5 * (bounds[r] + bounds[r + 1])
        blocks.append(
            f"\t\t<AngleBasisBlock>\n\t\t<Theta>{centre:g}</Theta>\n\t\t<nPhis>{n}</nPhis>\n"
            f"\t\t<ThetaBounds>\n\t\t\t<LowerTheta>{bounds[r]:g}</LowerTheta>\n"
            f"\t\t\t<UpperTheta>{bounds[r + 1]:g}</UpperTheta>\n\t\t</ThetaBounds>\n"
            f"\t\t</AngleBasisBlock>\n"
        )
    return f"\t<AngleBasis>\n\t\t<AngleBasisName>{name}</AngleBasisName>\n{''.join(blocks)}\t</AngleBasis>\n"


def block(direction, basis, structure, f):
    ps = patches(basis)
    n = len(ps)
    rows = []
    for a in range(n):
        # Columns: a row per outgoing patch; Rows: a row per incident patch.
        if structure == "Columns":
            row = [f(ps[i], ps[a]) for i in range(n)]
        else:
            row = [f(ps[a], ps[o]) for o in range(n)]
        rows.append(", ".join(f"{v:.6g}" for v in row))
    kind = "BTDF" if direction.startswith("Transmission") else "BRDF"
    return (
        "\t<WavelengthDataBlock>\n"
        f"\t\t<WavelengthDataDirection>{direction}</WavelengthDataDirection>\n"
        f"\t\t<ColumnAngleBasis>{basis}</ColumnAngleBasis>\n"
        f"\t\t<RowAngleBasis>{basis}</RowAngleBasis>\n"
        f"\t\t<ScatteringDataType>{kind}</ScatteringDataType>\n"
        "\t\t<ScatteringData>\n" + ",\n".join(rows) + "\n\t\t</ScatteringData>\n"
        "\t</WavelengthDataBlock>\n"
    )


def document(name, basis, structure, channels):
    """channels: (wavelength name, its WavelengthDataBlocks)."""
    data = "".join(
        "<WavelengthData>\n\t<LayerNumber>System</LayerNumber>\n"
        f'\t<Wavelength unit="Integral">{wavelength}</Wavelength>\n'
        "\t<SourceSpectrum>CIE Illuminant D65 1nm.ssp</SourceSpectrum>\n"
        f"\t<DetectorSpectrum>ASTM E308 1931 {wavelength[-1] if wavelength != 'Visible' else 'Y'}.dsp</DetectorSpectrum>\n"
        + "".join(blocks)
        + "</WavelengthData>\n"
        for wavelength, blocks in channels
    )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<WindowElement xmlns="http://windows.lbl.gov" '
        'xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" '
        'xsi:schemaLocation="http://windows.lbl.gov/BSDF-v1.4.xsd">\n'
        "<WindowElementType>System</WindowElementType>\n<FileType>BSDF</FileType>\n"
        f"<Optical>\n<Layer>\n\t<Material>\n\t\t<Name>{name}</Name>\n"
        "\t\t<DeviceType>Other</DeviceType>\n\t</Material>\n"
        f"\t<DataDefinition>\n\t<IncidentDataStructure>{structure}</IncidentDataStructure>\n"
        + basis_xml(basis)
        + "\t</DataDefinition>\n"
        + data
        + "</Layer>\n</Optical>\n</WindowElement>\n"
    )


def lobe(shift_deg, scale, absolute):
    return lambda i, o: scale * (1 + 0.9 * math.cos(o[1] - i[1] - math.radians(shift_deg))) * (
        0.5 + math.cos(o[0])
    ) * (1 + 0.7 * absolute(i[1], o[1]))


here = os.path.dirname(os.path.abspath(__file__))
full = "LBNL/Klems Full"
deflect = [
    block("Transmission Front", full, "Columns", lobe(90, 0.12, lambda pi_, po: math.sin(pi_))),
    block("Transmission Back", full, "Columns", lobe(-45, 0.09, lambda pi_, po: math.cos(po))),
    block("Reflection Front", full, "Columns", lambda i, o: 0.10 / math.pi),
    block("Reflection Back", full, "Columns", lambda i, o: 0.05 * (1 + 0.5 * math.cos(o[1] - i[1]))),
]
with open(os.path.join(here, "deflect.xml"), "w") as f:
    f.write(document("deflect", full, "Columns", [("Visible", deflect)]))
quarter = "LBNL/Klems Quarter"
def diffuser(k):
    return [
        block("Transmission Front", quarter, "Rows", lambda i, o: k * 0.35 / math.pi),
        block("Transmission Back", quarter, "Rows", lambda i, o: k * 0.35 / math.pi),
        block("Reflection Front", quarter, "Rows", lambda i, o: k * 0.2 / math.pi),
        block("Reflection Back", quarter, "Rows", lambda i, o: k * 0.2 / math.pi),
    ]


with open(os.path.join(here, "diffuser.xml"), "w") as f:
    f.write(document("diffuser", quarter, "Rows", [("Visible", diffuser(1))]))
with open(os.path.join(here, "tinted.xml"), "w") as f:
    tint = [("Visible", diffuser(1)), ("CIE-X", diffuser(1.2)), ("CIE-Z", diffuser(0.6))]
    f.write(document("tinted", quarter, "Rows", tint))
