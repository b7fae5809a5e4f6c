"""Quadrature rules as scikit-fem and SciPy computed them (hexadecimal floats), so that a job
evaluating norms needs neither library (their import is most of such a job's time) and gives
the same bits on every machine (SciPy's last bits depend on the machine:
docs/evidence/design-measurements.md#quadrature-tables).  Written by
``scripts/quadrature_tables.py``; ``tests/fem/test_quadrature_tables.py`` checks every rule
against the libraries."""

# scikit-fem's degree-8 rule on the reference triangle: points (2, 16) row by row, weights (16,)
DUNAVANT8_POINTS = (
    "0x1.555555555554fp-2", "0x1.d650cbd80cbc8p-2", "0x1.5d5370f3f61aep-3", "0x1.9e153890cd915p-5",
    "0x1.4d79a13f9a1c2p-4", "0x1.5156478604f29p-1", "0x1.cc3d58ede64dfp-1", "0x1.d650cbd80cbc8p-2",
    "0x1.5d5370f3f61aep-3", "0x1.9e153890cd906p-5", "0x1.74fcf47641a8dp-1", "0x1.0d6d7319c1522p-2",
    "0x1.13147f376b88ep-7", "0x1.13147f376b88ep-7", "0x1.0d6d7319c1522p-2", "0x1.74fcf47641a8dp-1",
    "0x1.555555555554fp-2", "0x1.4d79a13f9a1c2p-4", "0x1.5156478604f29p-1", "0x1.cc3d58ede64dfp-1",
    "0x1.d650cbd80cbc8p-2", "0x1.5d5370f3f61aep-3", "0x1.9e153890cd906p-5", "0x1.d650cbd80cbc8p-2",
    "0x1.5d5370f3f61aep-3", "0x1.9e153890cd915p-5", "0x1.13147f376b88ep-7", "0x1.13147f376b88ep-7",
    "0x1.0d6d7319c1522p-2", "0x1.74fcf47641a8dp-1", "0x1.74fcf47641a8dp-1", "0x1.0d6d7319c1522p-2",
)
DUNAVANT8_WEIGHTS = (
    "0x1.278ef0fa3a4a2p-4", "0x1.857ece34d1a43p-5", "0x1.a6c741ed362e6p-5", "0x1.09e667389b115p-6",
    "0x1.857ece34d1a43p-5", "0x1.a6c741ed362e6p-5", "0x1.09e667389b115p-6", "0x1.857ece34d1a43p-5",
    "0x1.a6c741ed362e6p-5", "0x1.09e667389b115p-6", "0x1.be243735b23c0p-7", "0x1.be243735b23c0p-7",
    "0x1.be243735b23c0p-7", "0x1.be243735b23c0p-7", "0x1.be243735b23c0p-7", "0x1.be243735b23c0p-7",
)
# scipy.special.roots_legendre(n): n -> (points, weights) on [-1, 1]
LEGENDRE = {
    3: ((
            "-0x1.8c97ef43f7248p-1", "0x0.0p+0", "0x1.8c97ef43f7248p-1",
        ), (
            "0x1.1c71c71c71c74p-1", "0x1.c71c71c71c717p-1", "0x1.1c71c71c71c74p-1",
        )),
    4: ((
            "-0x1.b8e6dbcf63985p-1", "-0x1.5c23fd9dd3dfdp-2", "0x1.5c23fd9dd3dfdp-2", "0x1.b8e6dbcf63985p-1",
        ), (
            "0x1.64340f7e7b66ap-2", "0x1.4de5f840c24cbp-1", "0x1.4de5f840c24cbp-1", "0x1.64340f7e7b66ap-2",
        )),
    5: ((
            "-0x1.cff6ce0533a69p-1", "-0x1.13b23fd99b705p-1", "0x0.0p+0", "0x1.13b23fd99b705p-1",
            "0x1.cff6ce0533a69p-1",
        ), (
            "0x1.e539ec36e0388p-3", "0x1.ea1da25ae415cp-2", "0x1.23456789abce0p-1", "0x1.ea1da25ae415cp-2",
            "0x1.e539ec36e0388p-3",
        )),
    7: ((
            "-0x1.e5f178e7c6228p-1", "-0x1.7ba9f9be3a1d6p-1", "-0x1.9f95df119fd62p-2", "0x0.0p+0",
            "0x1.9f95df119fd62p-2", "0x1.7ba9f9be3a1d6p-1", "0x1.e5f178e7c6228p-1",
        ), (
            "0x1.092f69f826d5fp-3", "0x1.1e6b1713d8643p-2", "0x1.86fe74ee32b3ap-2", "0x1.abfd7e03c2fa1p-2",
            "0x1.86fe74ee32b3ap-2", "0x1.1e6b1713d8643p-2", "0x1.092f69f826d5fp-3",
        )),
    8: ((
            "-0x1.ebab1cb0acc67p-1", "-0x1.97e4ab249f41ep-1", "-0x1.0d129583284b4p-1", "-0x1.77ac94f3c7346p-3",
            "0x1.77ac94f3c7346p-3", "0x1.0d129583284b4p-1", "0x1.97e4ab249f41ep-1", "0x1.ebab1cb0acc67p-1",
        ), (
            "0x1.9ea1d04ca0346p-4", "0x1.c76fb531d2b9fp-3", "0x1.413c50a25561bp-2", "0x1.736360b199344p-2",
            "0x1.736360b199344p-2", "0x1.413c50a25561bp-2", "0x1.c76fb531d2b9fp-3", "0x1.9ea1d04ca0346p-4",
        )),
    10: ((
            "-0x1.f2a3e062af2d8p-1", "-0x1.bae995e9cb2f2p-1", "-0x1.5bdb9228de198p-1", "-0x1.bbcc009016adcp-2",
            "-0x1.30e507891e278p-3", "0x1.30e507891e278p-3", "0x1.bbcc009016adcp-2", "0x1.5bdb9228de198p-1",
            "0x1.bae995e9cb2f2p-1", "0x1.f2a3e062af2d8p-1",
        ), (
            "0x1.1115f8b62dbd7p-4", "0x1.32138c878efe3p-3", "0x1.c0b059d00bc38p-3", "0x1.13baa7a559c05p-2",
            "0x1.2e9de7014d6f7p-2", "0x1.2e9de7014d6f7p-2", "0x1.13baa7a559c05p-2", "0x1.c0b059d00bc38p-3",
            "0x1.32138c878efe3p-3", "0x1.1115f8b62dbd7p-4",
        )),
    14: ((
            "-0x1.f8fa30fddab0ap-1", "-0x1.db5bd12b99e9fp-1", "-0x1.a786ee46dd9c4p-1", "-0x1.5fe4db09e0c89p-1",
            "-0x1.07ceab54ef096p-1", "-0x1.46c564912d702p-2", "-0x1.ba97d36de76adp-4", "0x1.ba97d36de76adp-4",
            "0x1.46c564912d702p-2", "0x1.07ceab54ef096p-1", "0x1.5fe4db09e0c89p-1", "0x1.a786ee46dd9c4p-1",
            "0x1.db5bd12b99e9fp-1", "0x1.f8fa30fddab0ap-1",
        ), (
            "0x1.1fb2d8b27f5ebp-5", "0x1.4853d8adc700ep-4", "0x1.f1bd74ef611b0p-4", "0x1.41f3bbee2d2f6p-3",
            "0x1.7bfb8e2a8f57ep-3", "0x1.a43f1796fab07p-3", "0x1.b8dc415514e2dp-3", "0x1.b8dc415514e2dp-3",
            "0x1.a43f1796fab07p-3", "0x1.7bfb8e2a8f57ep-3", "0x1.41f3bbee2d2f6p-3", "0x1.f1bd74ef611b0p-4",
            "0x1.4853d8adc700ep-4", "0x1.1fb2d8b27f5ebp-5",
        )),
    16: ((
            "-0x1.fa92c264d787ep-1", "-0x1.e39f56616f9b0p-1", "-0x1.bb3403514e483p-1", "-0x1.82c45dda4726bp-1",
            "-0x1.3c5a466d5e8b8p-1", "-0x1.d50259a43a773p-2", "-0x1.205cae642337cp-2", "-0x1.852bd6676a9fap-4",
            "0x1.852bd6676a9fap-4", "0x1.205cae642337cp-2", "0x1.d50259a43a773p-2", "0x1.3c5a466d5e8b8p-1",
            "0x1.82c45dda4726bp-1", "0x1.bb3403514e483p-1", "0x1.e39f56616f9b0p-1", "0x1.fa92c264d787ep-1",
        ), (
            "0x1.bcddab4b7c4bcp-6", "0x1.fdfb1a2c12637p-5", "0x1.85c4ee79cc236p-4", "0x1.fe7af2bad3858p-4",
            "0x1.325f61bca3cb2p-3", "0x1.5a6ebbb5a75edp-3", "0x1.75f8c77e0c004p-3", "0x1.83feae80e4deep-3",
            "0x1.83feae80e4deep-3", "0x1.75f8c77e0c004p-3", "0x1.5a6ebbb5a75edp-3", "0x1.325f61bca3cb2p-3",
            "0x1.fe7af2bad3858p-4", "0x1.85c4ee79cc236p-4", "0x1.fdfb1a2c12637p-5", "0x1.bcddab4b7c4bcp-6",
        )),
    20: ((
            "-0x1.fc7b5a0c71ce0p-1", "-0x1.ed8dba7bd769ep-1", "-0x1.d31064173fd92p-1", "-0x1.ada0bd5efd6e8p-1",
            "-0x1.7e1f37346a54ep-1", "-0x1.45a8d3fa710dap-1", "-0x1.05905c13f7ff6p-1", "-0x1.7eaccf15652c4p-2",
            "-0x1.d281636928bbfp-3", "-0x1.3973df98b86adp-4", "0x1.3973df98b86adp-4", "0x1.d281636928bbfp-3",
            "0x1.7eaccf15652c4p-2", "0x1.05905c13f7ff6p-1", "0x1.45a8d3fa710dap-1", "0x1.7e1f37346a54ep-1",
            "0x1.ada0bd5efd6e8p-1", "0x1.d31064173fd92p-1", "0x1.ed8dba7bd769ep-1", "0x1.fc7b5a0c71ce0p-1",
        ), (
            "0x1.209680274e953p-6", "0x1.4c9b5ea53b6cdp-5", "0x1.00b467df7e488p-4", "0x1.5519fe196e227p-4",
            "0x1.a1817a317a814p-4", "0x1.e41ff31573b48p-4", "0x1.0db2c5db26df8p-3", "0x1.230348f34a52bp-3",
            "0x1.31819b52c598dp-3", "0x1.38d6c490a3367p-3", "0x1.38d6c490a3367p-3", "0x1.31819b52c598dp-3",
            "0x1.230348f34a52bp-3", "0x1.0db2c5db26df8p-3", "0x1.e41ff31573b48p-4", "0x1.a1817a317a814p-4",
            "0x1.5519fe196e227p-4", "0x1.00b467df7e488p-4", "0x1.4c9b5ea53b6cdp-5", "0x1.209680274e953p-6",
        )),
    28: ((
            "-0x1.fe2db606d9717p-1", "-0x1.f66d5e557556ep-1", "-0x1.e894ac24695b6p-1", "-0x1.d4cdda1efbc1bp-1",
            "-0x1.bb5643c49dae1p-1", "-0x1.9c7d0698c9ac0p-1", "-0x1.78a1fd2f4d007p-1", "-0x1.5034927b8f20ap-1",
            "-0x1.23b266d495548p-1", "-0x1.e74b92a4c42d8p-2", "-0x1.814813d2b129dp-2", "-0x1.169752c4c22bap-2",
            "-0x1.5109b3258335fp-3", "-0x1.c335a497a4801p-5", "0x1.c335a497a4801p-5", "0x1.5109b3258335fp-3",
            "0x1.169752c4c22bap-2", "0x1.814813d2b129dp-2", "0x1.e74b92a4c42d8p-2", "0x1.23b266d495548p-1",
            "0x1.5034927b8f20ap-1", "0x1.78a1fd2f4d007p-1", "0x1.9c7d0698c9ac0p-1", "0x1.bb5643c49dae1p-1",
            "0x1.d4cdda1efbc1bp-1", "0x1.e894ac24695b6p-1", "0x1.f66d5e557556ep-1", "0x1.fe2db606d9717p-1",
        ), (
            "0x1.2afc07ab1c16fp-7", "0x1.5a3a811ece5f9p-6", "0x1.0d874b8a22761p-5", "0x1.6aaf12dc69604p-5",
            "0x1.c3707aee4a4d3p-5", "0x1.0b5b9f1c0a7a7p-4", "0x1.31c03a8e85dd7p-4", "0x1.546ebc0db6012p-4",
            "0x1.72fb5b81c186ep-4", "0x1.8d0729614b3e9p-4", "0x1.a2413503ecaa1p-4", "0x1.b26787e30dbfcp-4",
            "0x1.bd47f27756304p-4", "0x1.c2c0a81eda1a6p-4", "0x1.c2c0a81eda1a6p-4", "0x1.bd47f27756304p-4",
            "0x1.b26787e30dbfcp-4", "0x1.a2413503ecaa1p-4", "0x1.8d0729614b3e9p-4", "0x1.72fb5b81c186ep-4",
            "0x1.546ebc0db6012p-4", "0x1.31c03a8e85dd7p-4", "0x1.0b5b9f1c0a7a7p-4", "0x1.c3707aee4a4d3p-5",
            "0x1.6aaf12dc69604p-5", "0x1.0d874b8a22761p-5", "0x1.5a3a811ece5f9p-6", "0x1.2afc07ab1c16fp-7",
        )),
    32: ((
            "-0x1.fe995e70409b6p-1", "-0x1.f8a212714bcdcp-1", "-0x1.edf5518053baap-1", "-0x1.deac0259f7f42p-1",
            "-0x1.caea9b4574cb9p-1", "-0x1.b2e04fd686a12p-1", "-0x1.96c69481c4bc4p-1", "-0x1.76e0931d693bap-1",
            "-0x1.537a89c487f8ap-1", "-0x1.2ce9146962ca4p-1", "-0x1.038862866b29ep-1", "-0x1.af76b57c6f8f2p-2",
            "-0x1.53d55ce57bdf6p-2", "-0x1.ea0f7e19c094cp-3", "-0x1.27e0ea717f235p-3", "-0x1.8bbc8488cc49cp-5",
            "0x1.8bbc8488cc49cp-5", "0x1.27e0ea717f235p-3", "0x1.ea0f7e19c094cp-3", "0x1.53d55ce57bdf6p-2",
            "0x1.af76b57c6f8f2p-2", "0x1.038862866b29ep-1", "0x1.2ce9146962ca4p-1", "0x1.537a89c487f8ap-1",
            "0x1.76e0931d693bap-1", "0x1.96c69481c4bc4p-1", "0x1.b2e04fd686a12p-1", "0x1.caea9b4574cb9p-1",
            "0x1.deac0259f7f42p-1", "0x1.edf5518053baap-1", "0x1.f8a212714bcdcp-1", "0x1.fe995e70409b6p-1",
        ), (
            "0x1.cbf8bc743dfd5p-8", "0x1.0aa3c248694f0p-6", "0x1.a0060a8531f15p-6", "0x1.18c5800a35559p-5",
            "0x1.5ee963a3354e0p-5", "0x1.a1c6ae961fc05p-5", "0x1.e0bd76c9249a4p-5", "0x1.0d9b9a62cabebp-4",
            "0x1.2854103b35e0bp-4", "0x1.40483e126fd09p-4", "0x1.553ee25ebebb2p-4", "0x1.6705e18e13ec9p-4",
            "0x1.7572bdb3f6e3fp-4", "0x1.8062fc0f6feeep-4", "0x1.87bc776f8c6c8p-4", "0x1.8b6d9eaec779ep-4",
            "0x1.8b6d9eaec779ep-4", "0x1.87bc776f8c6c8p-4", "0x1.8062fc0f6feeep-4", "0x1.7572bdb3f6e3fp-4",
            "0x1.6705e18e13ec9p-4", "0x1.553ee25ebebb2p-4", "0x1.40483e126fd09p-4", "0x1.2854103b35e0bp-4",
            "0x1.0d9b9a62cabebp-4", "0x1.e0bd76c9249a4p-5", "0x1.a1c6ae961fc05p-5", "0x1.5ee963a3354e0p-5",
            "0x1.18c5800a35559p-5", "0x1.a0060a8531f15p-6", "0x1.0aa3c248694f0p-6", "0x1.cbf8bc743dfd5p-8",
        )),
    64: ((
            "-0x1.ffa4e911f7532p-1", "-0x1.fe204ab274eccp-1", "-0x1.fb661ac8c85a8p-1", "-0x1.f777d976cfadap-1",
            "-0x1.f257e4db5aabcp-1", "-0x1.ec09586b58faap-1", "-0x1.e490081f2891bp-1", "-0x1.dbf07d935a5afp-1",
            "-0x1.d22ff5221288ap-1", "-0x1.c7545aa8c0dacp-1", "-0x1.bb6445eadae2cp-1", "-0x1.ae66f68eedbc6p-1",
            "-0x1.a0644fb6d8db8p-1", "-0x1.9164d335425e2p-1", "-0x1.81719c62ec68ep-1", "-0x1.70945a96f12c4p-1",
            "-0x1.5ed74b4532f82p-1", "-0x1.4c4533c68b412p-1", "-0x1.38e95ace7b3c3p-1", "-0x1.24cf81925487ep-1",
            "-0x1.1003dca600f34p-1", "-0x1.f52619257c3a2p-2", "-0x1.c9142c5898fc6p-2", "-0x1.9becb55272c9dp-2",
            "-0x1.6dcb1f0621000p-2", "-0x1.3ecb6c46c76cap-2", "-0x1.0f0a26c56e49cp-2", "-0x1.bd489b79ec839p-3",
            "-0x1.5b6e88ad5c00fp-3", "-0x1.f182ff48e8a28p-4", "-0x1.2afad5ee95ad0p-4", "-0x1.8ef487a8cbc22p-6",
            "0x1.8ef487a8cbc22p-6", "0x1.2afad5ee95ad0p-4", "0x1.f182ff48e8a28p-4", "0x1.5b6e88ad5c00fp-3",
            "0x1.bd489b79ec839p-3", "0x1.0f0a26c56e49cp-2", "0x1.3ecb6c46c76cap-2", "0x1.6dcb1f0621000p-2",
            "0x1.9becb55272c9dp-2", "0x1.c9142c5898fc6p-2", "0x1.f52619257c3a2p-2", "0x1.1003dca600f34p-1",
            "0x1.24cf81925487ep-1", "0x1.38e95ace7b3c3p-1", "0x1.4c4533c68b412p-1", "0x1.5ed74b4532f82p-1",
            "0x1.70945a96f12c4p-1", "0x1.81719c62ec68ep-1", "0x1.9164d335425e2p-1", "0x1.a0644fb6d8db8p-1",
            "0x1.ae66f68eedbc6p-1", "0x1.bb6445eadae2cp-1", "0x1.c7545aa8c0dacp-1", "0x1.d22ff5221288ap-1",
            "0x1.dbf07d935a5afp-1", "0x1.e490081f2891bp-1", "0x1.ec09586b58faap-1", "0x1.f257e4db5aabcp-1",
            "0x1.f777d976cfadap-1", "0x1.fb661ac8c85a8p-1", "0x1.fe204ab274eccp-1", "0x1.ffa4e911f7532p-1",
        ), (
            "0x1.d379f18462606p-10", "0x1.0fc7ac3ac30d8p-8", "0x1.aa46b24146121p-8", "0x1.21e400109d377p-7",
            "0x1.6df524de84d07p-7", "0x1.b9283b35dfb4ep-7", "0x1.01a7c0a5c9846p-6", "0x1.261ef40a7a249p-6",
            "0x1.49e391bd2151ap-6", "0x1.6cdfe10bba3c3p-6", "0x1.8efea346845d1p-6", "0x1.b02b2071c0ba8p-6",
            "0x1.d05133c3af938p-6", "0x1.ef5d57d53b41ep-6", "0x1.069e593b92357p-5", "0x1.14ee9010d92b1p-5",
            "0x1.22969f7b5c8f2p-5", "0x1.2f8e3ca7574d9p-5", "0x1.3bcd87e50ddf2p-5", "0x1.474d11709281dp-5",
            "0x1.5205ddf5a36c8p-5", "0x1.5bf16accdf401p-5", "0x1.6509b1efb8ddap-5", "0x1.6d492da0c24f4p-5",
            "0x1.74aadbc614f94p-5", "0x1.7b2a40f3ccde1p-5", "0x1.80c36b24bdd01p-5", "0x1.8572f41fbb52ep-5",
            "0x1.89360387fe3a0p-5", "0x1.8c0a5097676b3p-5", "0x1.8dee238192ccap-5", "0x1.8ee0567ee2e42p-5",
            "0x1.8ee0567ee2e42p-5", "0x1.8dee238192ccap-5", "0x1.8c0a5097676b3p-5", "0x1.89360387fe3a0p-5",
            "0x1.8572f41fbb52ep-5", "0x1.80c36b24bdd01p-5", "0x1.7b2a40f3ccde1p-5", "0x1.74aadbc614f94p-5",
            "0x1.6d492da0c24f4p-5", "0x1.6509b1efb8ddap-5", "0x1.5bf16accdf401p-5", "0x1.5205ddf5a36c8p-5",
            "0x1.474d11709281dp-5", "0x1.3bcd87e50ddf2p-5", "0x1.2f8e3ca7574d9p-5", "0x1.22969f7b5c8f2p-5",
            "0x1.14ee9010d92b1p-5", "0x1.069e593b92357p-5", "0x1.ef5d57d53b41ep-6", "0x1.d05133c3af938p-6",
            "0x1.b02b2071c0ba8p-6", "0x1.8efea346845d1p-6", "0x1.6cdfe10bba3c3p-6", "0x1.49e391bd2151ap-6",
            "0x1.261ef40a7a249p-6", "0x1.01a7c0a5c9846p-6", "0x1.b9283b35dfb4ep-7", "0x1.6df524de84d07p-7",
            "0x1.21e400109d377p-7", "0x1.aa46b24146121p-8", "0x1.0fc7ac3ac30d8p-8", "0x1.d379f18462606p-10",
        )),
}
# scipy.special.roots_jacobi(n, 0, 1): n -> (points, weights), weight (1 + x) on [-1, 1]
JACOBI01 = {
    3: ((
            "-0x1.269033b297590p-1", "0x1.72d2df86e6edfp-3", "0x1.a54932ac4b548p-1",
        ), (
            "0x1.1e02e530e2141p-2", "0x1.d57c5c75b4cc9p-1", "0x1.9b8230f1da297p-1",
        )),
    4: ((
            "-0x1.70e2ca456677bp-1", "-0x1.5662ebd487286p-3", "0x1.c90687b262aa3p-2", "0x1.c5867a44e525ap-1",
        ), (
            "0x1.fede789f384a2p-4", "0x1.09ed82d38b984p-1", "0x1.a0b2080bfdb6cp-1", "0x1.1584a60c8fa7bp-1",
        )),
    5: ((
            "-0x1.9b199e53f1237p-1", "-0x1.904f92acb8e06p-2", "0x1.fc1c403080601p-4", "0x1.353bf87841330p-1",
            "0x1.d73c15b79f3d3p-1",
        ), (
            "0x1.02038a7674ae5p-4", "0x1.2ebb113d8a0a8p-2", "0x1.2bccf0d0b5843p-1", "0x1.565fa81ab0082p-1",
            "0x1.8c6ada4e0db12p-2",
        )),
    7: ((
            "-0x1.c6631b7a04cfdp-1", "-0x1.476efbee5396ep-1", "-0x1.2dd317a1e6c76p-2", "0x1.8248525f48019p-4",
            "0x1.dfa995dc3e926p-2", "0x1.8a9193048cf99p-1", "0x1.e8fb29e9a5764p-1",
        ), (
            "0x1.55ba7b216c23bp-6", "0x1.c10efaf07bab6p-4", "0x1.0fe966446302dp-2", "0x1.b6c8c5dbee184p-2",
            "0x1.04e584cdadb99p-1", "0x1.c4a55b1d5c453p-2", "0x1.ca7c117182ff3p-3",
        )),
    8: ((
            "-0x1.d24b79f6f42d3p-1", "-0x1.6c2b407d6ea60p-1", "-0x1.b49538c30d5edp-2", "-0x1.722b58ae40885p-4",
            "0x1.06486de6465c8p-2", "0x1.248c5166f60afp-1", "0x1.a27c106adee1bp-1", "0x1.edcb1a17aa69cp-1",
        ), (
            "0x1.afe846f5003b5p-7", "0x1.24568ed7e20dep-4", "0x1.743d28e734a60p-3", "0x1.4466cc9ad01d4p-2",
            "0x1.b25eb749abef5p-2", "0x1.ccd2e195679c0p-2", "0x1.753938a8fca01p-2", "0x1.6cf5cef7c9bf1p-3",
        )),
    10: ((
            "-0x1.e14011c3be584p-1", "-0x1.9b5a200c0298bp-1", "-0x1.3433d17a8e2dfp-1", "-0x1.685591e68241cp-2",
            "-0x1.2cf6c6a7d03a7p-4", "0x1.af8e20bed564cp-3", "0x1.e9251da413ea7p-2", "0x1.695b9dbba9d7ep-1",
            "0x1.c0c94ec8b17ccp-1", "0x1.f3cbde803ee0ep-1",
        ), (
            "0x1.88fd9f701153ap-8", "0x1.13e25f8fad620p-5", "0x1.75238f5e2d7a2p-4", "0x1.638c651349d9dp-3",
            "0x1.0e8dab7584541p-2", "0x1.5a588e4c43205p-2", "0x1.7bafbcec95f5ep-2", "0x1.611f19b49a32bp-2",
            "0x1.0751f7a2b5e5ap-2", "0x1.ed267ca5b1019p-4",
        )),
    14: ((
            "-0x1.ef62c66445deap-1", "-0x1.c90393338063bp-1", "-0x1.8eafe19b401a3p-1", "-0x1.42f587219d5fap-1",
            "-0x1.d2480839d4547p-2", "-0x1.0a50acdea5f25p-2", "-0x1.b612b8014361bp-5", "0x1.3e47f5196a533p-3",
            "0x1.6e0914738252dp-2", "0x1.167113b35154ap-1", "0x1.69abfc19a98dbp-1", "0x1.ad12231da9c35p-1",
            "0x1.ddb1cecca8e55p-1", "0x1.f96de278fe8e5p-1",
        ), (
            "0x1.cd12bffa8f6b9p-10", "0x1.4ec56b42a18bdp-7", "0x1.de2eb0ba59ad7p-6", "0x1.ec941a7b5ae85p-5",
            "0x1.a089be1e61566p-4", "0x1.32bbdd5812fbcp-3", "0x1.95a9d2b62c5e1p-3", "0x1.e9c36798cb92fp-3",
            "0x1.0ff16cea4c313p-2", "0x1.15d6a67a22477p-2", "0x1.02eba9585e06dp-2", "0x1.ada322e325033p-3",
            "0x1.2956648714096p-3", "0x1.0b7f5ef7626a3p-4",
        )),
    20: ((
            "-0x1.f78031764d194p-1", "-0x1.e3b18a178e7f9p-1", "-0x1.c515afe83a26bp-1", "-0x1.9c5c4e7e592ecp-1",
            "-0x1.6a6e656c90f9dp-1", "-0x1.306983e091737p-1", "-0x1.df32edd74ffd7p-2", "-0x1.52e1c70a39a5cp-2",
            "-0x1.7e0400027d8e4p-3", "-0x1.3709e0c7a8b16p-5", "0x1.c86a38cccbe9fp-4", "0x1.08868429fe4c8p-2",
            "0x1.990671caf3674p-2", "0x1.1030008d2da43p-1", "0x1.4dc697fd11876p-1", "0x1.83e6cdacf3f33p-1",
            "0x1.b15b1f11941f1p-1", "0x1.d51fa7d2d994dp-1", "0x1.ee680bf7d7bddp-1", "0x1.fca53033fe2e0p-1",
        ), (
            "0x1.e3f26124c6fefp-12", "0x1.661f111869b9ep-9", "0x1.07a55156aa009p-7", "0x1.1b5394b3d386ep-6",
            "0x1.fa70c108aeefdp-6", "0x1.8fe6f57f19851p-5", "0x1.204f72b01c17fp-4", "0x1.8313ac9b1e01dp-4",
            "0x1.e9e8fed3ae83cp-4", "0x1.269fe6f236448p-3", "0x1.527982f0bed69p-3", "0x1.747ebc8ddae90p-3",
            "0x1.8918ce898aa11p-3", "0x1.8d71a591f6c58p-3", "0x1.7fba25d472a61p-3", "0x1.5f5b783e1381cp-3",
            "0x1.2d0ed6c6fe709p-3", "0x1.d5b34d7e8c96ep-4", "0x1.37de72d4ecdd4p-4", "0x1.124bbafd0e675p-5",
        )),
    28: ((
            "-0x1.fb898d617f5f0p-1", "-0x1.f117423d5165ep-1", "-0x1.e0d10dc578f41p-1", "-0x1.cae81c77b9451p-1",
            "-0x1.af9e3fc5acf56p-1", "-0x1.8f45631c47a7ep-1", "-0x1.6a3e9dfce0bfdp-1", "-0x1.40f912600126ep-1",
            "-0x1.13f09fb2416b7p-1", "-0x1.c758de79166efp-2", "-0x1.617abd1b4ba15p-2", "-0x1.eef132e16c85fp-3",
            "-0x1.15213e15dbe1dp-3", "-0x1.c09abfa67c65dp-6", "0x1.4b4210ee4bc32p-4", "0x1.81627884ce1c7p-3",
            "0x1.2c4eb38a78d9ap-2", "0x1.9465ec17365fcp-2", "0x1.f7be7bec8100cp-2", "0x1.2a971b5f77d46p-1",
            "0x1.55ce56758b0acp-1", "0x1.7d033a9de7063p-1", "0x1.9fc01bd89c0a8p-1", "0x1.bd9cb82bce1e5p-1",
            "0x1.d63f7148855dfp-1", "0x1.e95e5c3f6f694p-1", "0x1.f6c02df1d9383p-1", "0x1.fe3d81bbaa80fp-1",
        ), (
            "0x1.0b32e5082b5a9p-13", "0x1.8f2d127d2f674p-11", "0x1.2a4310e1efb37p-9", "0x1.4727442a86837p-8",
            "0x1.2c30325ea5edep-7", "0x1.e9bba1b2a001cp-7", "0x1.6f243eaee647cp-6", "0x1.021b4483deb61p-5",
            "0x1.58cd90426285fp-5", "0x1.b991f0e30bd8fp-5", "0x1.10c515680ee9bp-4", "0x1.46971a545b0dcp-4",
            "0x1.7c393f6af8962p-4", "0x1.af7ab42f3717fp-4", "0x1.de18e4df88fe9p-4", "0x1.02ed0f9fc7fe5p-3",
            "0x1.12542c8675792p-3", "0x1.1c556b9ac86edp-3", "0x1.202ec059e6f34p-3", "0x1.1d52611ef071cp-3",
            "0x1.136e87c5ef2b2p-3", "0x1.0272a1068e4fcp-3", "0x1.d523514b458e9p-4", "0x1.988324ceda12ep-4",
            "0x1.506f8a735a059p-4", "0x1.fd8b849f84dbcp-5", "0x1.4b8af6da13baep-5", "0x1.205da03c8aa7cp-6",
        )),
}
