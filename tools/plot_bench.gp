# Log-log plot of RMSE against render time, one line per method.
# gnuplot -e "csv='bench.csv'; out='bench.png'" tools/plot_bench.gp
set datafile separator ","
set terminal pngcairo size 800,560 noenhanced
set output out
set logscale xy
set xlabel "render time (s)"
set ylabel "RMSE against the reference"
set grid
set key top right
methods = system("tail -n +2 '".csv."' | cut -d, -f1 | awk '!seen[$0]++' | tr '\\n' ' '")
plot for [m in methods] csv using (strcol(1) eq m ? $4 : 1/0):(strcol(1) eq m ? $5 : 1/0) with linespoints lw 2 pt 7 title m
