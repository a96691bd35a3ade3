; TF5200 programming manual, "Reaction on contour change": G41 to G42 without G40, the radius by D
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/207823755.html
; adapted: the page's V.G.WZR=2 (radius 2 mm) replaced by D4, the fixture's tools.lis tool 4 of
; radius 2 mm (the page as written is trc_contour_change.nc).
; expect: end X=0 Y=0
; expect: blocks N05 N10 N20 N30 N40 N50
N05 G01 Y10 F100 G41 D4
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
