; TF5200 programming manual, "Zero offsets (G53/G54/...G59)": zero offset using V.G. variables
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206487307.html
; adapted: the first part of the page's example; M30 appended.
; expect: end X=110
; set zero offset for the X axis (channel axis)
V.G.NP[1].V.X=10
; activate zero offset
G54 ; corresponds to group [1]
G0 X=100 ; move along axis, considering zero offset
M30
