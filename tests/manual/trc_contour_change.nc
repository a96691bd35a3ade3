; TF5200 programming manual, "Reaction on contour change": G41 to G42 without G40
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/207823755.html
; adapted: none.
; expect: end X=0 Y=0
N05 G01 Y10 F100 G41 V.G.WZR=2
(Linear block with select. of TRC left)
(of the contour )
N10 X20 Y25
N20 X40 G42
(Linear block with select. of TRC right)
(of the contour)
N30 X60 Y10
N40 X0 Y0 G40
(Deselect TRC)
N50 M30
