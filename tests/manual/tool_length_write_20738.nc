; TF5200 diagnosis, ID 20738 "Write access to tool length is not allowed with D code in the same block.": the syntax example
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/252369035.html
; adapted: M30 appended (D1 is the fixture's tools.lis tool 1).
; expect: error 20738
N10 V.G.WZ_AKT.L=25 X10 Y20 D1
N20 M30
