; TF5200 programming manual, "Zero offsets (G53/G54/...G59)": selecting a zero offset in G91 mode
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206487307.html
; adapted: M30 appended.
; expect: end X=0
; expect: runs N20 1
N10 G54
N20 G0 X0 G91       (does not call motion on the X axis)
N30 M30
